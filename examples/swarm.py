#!/usr/bin/env python
"""A swarm from one script: every drone online on the router, commanded as one fleet.

The drones are found by their bridges' liveliness (``Fleet.connect``), take off together to
staggered heights (so they never share an altitude), fly a square together, corner by corner,
and land together; each step is one call to all, with one outcome per drone. Start a fleet of
simulated aircraft first:

    dronewrapper up compose/sim_fleet.yaml --var drones=3 &
    python examples/swarm.py [--names drone1 drone2 drone3] [--count 3] [--connect ENDPOINT]
"""

import argparse

from dronewrapper import DroneWrapper
from dronewrapper.fleet import Fleet

CORNERS = ((1.0, 0.0), (1.0, 1.0), (0.0, 1.0), (0.0, 0.0))
"""The square's corners, in sides, from each drone's position after take-off."""


def reached(drone: DroneWrapper, x: float, y: float, tolerance: float = 0.2) -> bool:
    position = drone.get_position()
    return abs(position[0] - x) < tolerance and abs(position[1] - y) < tolerance


def fly(fleet: Fleet, heights: dict[str, float], side: float) -> None:
    """Take off, fly the square corner by corner (every drone at once), land."""
    fleet.each(lambda d: d.takeoff(h=heights[d.ns]), what="takeoff").raise_errors()
    starts = fleet.each(lambda d: tuple(d.get_position()[:2]), what="position").raise_errors()
    for cx, cy in CORNERS:
        goals = {n: (x + cx * side, y + cy * side) for n, (x, y) in starts.results().items()}
        fleet.set_cmd_pos({n: (*goals[n], heights[n]) for n in goals}).raise_errors()
        fleet.each(
            lambda d, goals=goals: d.wait_for(lambda: reached(d, *goals[d.ns]), 30, d.ns),
            what=f"corner ({cx:g}, {cy:g})",
        ).raise_errors()
        print(f"corner ({cx * side:g}, {cy * side:g}) reached by all")
    fleet.land().raise_errors()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0], allow_abbrev=False)
    parser.add_argument("--names", nargs="+", help="namespaces (default: every drone online)")
    parser.add_argument("--count", type=int, help="wait until this many drones are online")
    parser.add_argument("--connect", default=None, help="router endpoint")
    parser.add_argument("--height", type=float, default=1.0, help="lowest flight height, m")
    parser.add_argument("--spacing", type=float, default=0.5, help="height step between drones")
    parser.add_argument("--side", type=float, default=1.0, help="square side, m")
    args = parser.parse_args()

    with Fleet.connect(args.names, args.connect, count=args.count, cameras=()) as fleet:
        print(f"swarm of {len(fleet)}: {', '.join(fleet.names)}")
        for info in fleet.online():
            print(f"  {info.name}: {info.kind}, {'healthy' if info.healthy else 'NOT healthy'}")
        heights = {n: args.height + i * args.spacing for i, n in enumerate(fleet.names)}
        try:
            fly(fleet, heights, args.side)
        except BaseException:
            fleet.land()  # whatever failed, nobody stays up
            raise
        for name, height in heights.items():
            print(f"{name}: flew its square at {height:g} m and landed")


if __name__ == "__main__":
    main()
