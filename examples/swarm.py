#!/usr/bin/env python
"""A swarm from one script: every drone online on the router, one DroneWrapper each.

The drones are found by their bridges' liveliness (``list_drones``), take off together to
staggered heights (so they never share an altitude), each fly a square of their own, and land
together. Start a few simulated aircraft on one router first:

    dronewrapper router &
    for n in 1 2 3; do
      dronewrapper up compose/sim_iris.yaml --use-router --ns drone$n \\
          --var onboard_port=1454$n --var gcs_port=1455$n &
    done
    python examples/swarm.py [--names drone1 drone2 drone3] [--connect tcp/127.0.0.1:7447]
"""

import argparse
import contextlib
from concurrent.futures import ThreadPoolExecutor

from dronewrapper import DroneWrapper, list_drones


def fly_square(drone: DroneWrapper, height: float, side: float) -> str:
    """Take off to ``height``, visit the corners of a ``side`` m square, come back; a summary."""
    drone.takeoff(h=height)
    x0, y0, _ = drone.get_position()
    for dx, dy in ((side, 0.0), (side, side), (0.0, side), (0.0, 0.0)):
        drone.set_cmd_pos(x0 + dx, y0 + dy, height)
        drone.wait_for(
            lambda dx=dx, dy=dy: (
                abs(drone.get_position()[0] - x0 - dx) < 0.2
                and abs(drone.get_position()[1] - y0 - dy) < 0.2
            ),
            30,
            f"{drone.ns} corner ({dx:g}, {dy:g})",
        )
    drone.land()
    return f"{drone.ns}: flew its square at {height:g} m and landed"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--names", nargs="+", help="namespaces (default: every drone online)")
    parser.add_argument("--connect", default=None, help="router endpoint")
    parser.add_argument("--height", type=float, default=1.0, help="lowest flight height, m")
    parser.add_argument("--spacing", type=float, default=0.5, help="height step between drones")
    parser.add_argument("--side", type=float, default=1.0, help="square side, m")
    args = parser.parse_args()

    names = args.names or list_drones(args.connect)
    print(f"swarm of {len(names)}: {', '.join(names)}")
    with contextlib.ExitStack() as stack:
        drones = [
            stack.enter_context(DroneWrapper(ns, args.connect, cameras=(), land_on_exit=True))
            for ns in names
        ]
        heights = [args.height + i * args.spacing for i in range(len(drones))]
        with ThreadPoolExecutor(len(drones)) as pool:  # all at once, each at its own height
            for summary in pool.map(fly_square, drones, heights, [args.side] * len(drones)):
                print(summary)


if __name__ == "__main__":
    main()
