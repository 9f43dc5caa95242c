#!/usr/bin/env python
"""Fly a square with position control (set_cmd_pos), then land.

Corners are in the local ENU frame (x east, y north, metres from the take-off point); the drone
faces the direction it flies. Leaving the ``with`` block lands it, even after an error or Ctrl-C.

    python examples/square.py [--side 2] [--height 2] [--name drone] [--connect tcp/...:7447]
"""

import argparse
import math

import numpy as np

from dronewrapper import DroneWrapper


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0], allow_abbrev=False)
    parser.add_argument("--side", type=float, default=2.0, help="side length, m")
    parser.add_argument("--height", type=float, default=2.0, help="flight altitude, m")
    parser.add_argument("--tolerance", type=float, default=0.3, help="corner reached within, m")
    parser.add_argument("--name", default=None, help="drone namespace (default: drone)")
    parser.add_argument("--connect", default=None, help="router endpoint")
    args = parser.parse_args()

    with DroneWrapper(args.name, args.connect, land_on_exit=True) as drone:
        drone.takeoff(h=args.height)
        x0, y0, z = drone.get_position()
        s = args.side
        for dx, dy in [(s, 0.0), (s, s), (0.0, s), (0.0, 0.0)]:
            corner = np.array([x0 + dx, y0 + dy])
            heading = math.atan2(*(corner - drone.get_position()[:2])[::-1])
            drone.set_cmd_pos(corner[0], corner[1], z, heading)
            drone.wait_for(
                lambda c=corner: np.linalg.norm(drone.get_position()[:2] - c) < args.tolerance,
                timeout=30,
                what=f"corner ({corner[0]:.1f}, {corner[1]:.1f})",
            )
            x, y, _ = drone.get_position()
            print(f"corner reached: x={x:.2f} y={y:.2f} z={drone.get_position()[2]:.2f}")
        print("square done, landing")
    print("landed")


if __name__ == "__main__":
    main()
