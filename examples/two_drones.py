#!/usr/bin/env python
"""Two drones at once: each DroneWrapper is one aircraft, chosen by its namespace.

Both take off (in parallel), fly apart with velocity control for a few seconds, turn back,
and land. Run two aircraft first, e.g. two simulators with their bridges on one router:

    dronewrapper router &
    dronewrapper up compose/sim_iris.yaml --use-router --ns drone1 --var onboard_port=14541 \
        --var gcs_port=14551 &
    dronewrapper up compose/sim_iris.yaml --use-router --ns drone2 --var onboard_port=14542 \
        --var gcs_port=14552 &
    python examples/two_drones.py [--names drone1 drone2] [--connect tcp/127.0.0.1:7447]
"""

import argparse
import time
from concurrent.futures import ThreadPoolExecutor

from dronewrapper import DroneWrapper, list_drones


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--names", nargs=2, default=["drone1", "drone2"])
    parser.add_argument("--connect", default=None, help="router endpoint")
    parser.add_argument("--height", type=float, default=2.0)
    parser.add_argument("--seconds", type=float, default=3.0, help="flight time each way")
    args = parser.parse_args()

    print("drones online:", ", ".join(list_drones(args.connect)))
    first, second = args.names
    with (
        DroneWrapper(first, args.connect, cameras=(), land_on_exit=True) as one,
        DroneWrapper(second, args.connect, cameras=(), land_on_exit=True) as two,
    ):
        drones = (one, two)
        with ThreadPoolExecutor(2) as pool:  # take off together
            list(pool.map(lambda d: d.takeoff(h=args.height), drones))
        one.set_cmd_vel(vx=1.0)  # forward
        two.set_cmd_vel(vx=-1.0)  # backward
        time.sleep(args.seconds)
        for d in drones:
            print(f"{d.ns}: position {d.get_position().round(2)}")
        one.set_cmd_vel(vx=-1.0)
        two.set_cmd_vel(vx=1.0)
        time.sleep(args.seconds)
        with ThreadPoolExecutor(2) as pool:  # land together
            list(pool.map(lambda d: d.land(), drones))
        for d in drones:
            print(f"{d.ns}: landed at {d.get_position().round(2)}")


if __name__ == "__main__":
    main()
