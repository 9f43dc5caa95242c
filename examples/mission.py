#!/usr/bin/env python
"""Fly a mission (a square of waypoints, as QGroundControl would upload it), then return home.

The waypoints are latitude/longitude degrees and metres above home, built from the drone's own
GPS fix; the bridge checks each against its safety envelope before the upload, and the
autopilot flies them in its mission mode. A ``.plan`` file from QGroundControl works the same:
``drone.upload_mission("survey.plan")``.

    python examples/mission.py [--side 8] [--height 4] [--name drone] [--connect tcp/...:7447]
"""

import argparse
import time

from dronewrapper import DroneWrapper
from dronewrapper.geodesy import to_geodetic


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0], allow_abbrev=False)
    parser.add_argument("--side", type=float, default=8.0, help="side length, m")
    parser.add_argument("--height", type=float, default=4.0, help="altitude above home, m")
    parser.add_argument("--name", default=None, help="drone namespace (default: drone)")
    parser.add_argument("--connect", default=None, help="router endpoint")
    args = parser.parse_args()

    with DroneWrapper(args.name, args.connect, land_on_exit=True) as drone:
        drone.takeoff(h=args.height)
        lat, lon, _ = drone.get_global_position()
        s, h = args.side, args.height
        corners = [(s, 0.0), (s, s), (0.0, s), (0.0, 0.0)]  # east, north m from here
        plan = [(*to_geodetic((lat, lon), east, north), h) for east, north in corners]
        print(f"uploaded {drone.upload_mission(plan)} waypoints")
        drone.start_mission()
        deadline = time.monotonic() + 120
        while not drone.mission_progress().finished and time.monotonic() < deadline:
            time.sleep(0.2)
        progress = drone.mission_progress()
        print(f"mission: reached {progress.reached_count} of {progress.total}")
        drone.return_to_launch()
        x, y, _ = drone.get_position()
        print(f"home: landed at x={x:.2f} y={y:.2f}")


if __name__ == "__main__":
    main()
