"""``dronewrapper station``: the web ground station (loopback by default).

Watch, teleoperate and command the drones online, and the simulated world, from a browser.
"""

from __future__ import annotations

import argparse
from collections.abc import Sequence

from dronewrapper.runtime.service import run_service
from dronewrapper_ground_station.config import Config
from dronewrapper_ground_station.node import PORTS, run


def _add_args(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--host", help="address to serve on (default 127.0.0.1)")
    parser.add_argument("--port", type=int, help="TCP port (default 8080; 0: any free port)")


def _configure(args: argparse.Namespace, overrides: list[str]) -> None:
    if args.host is not None:
        overrides.append(f"host={args.host}")
    if args.port is not None:
        overrides.append(f"port={args.port}")


def main(argv: Sequence[str] | None = None) -> int:
    """Run the station (``argv`` without the program name)."""
    return run_service(
        "station",
        __doc__,
        Config,
        run,
        argv,
        add_args=_add_args,
        configure=_configure,
        ports=PORTS,
    )
