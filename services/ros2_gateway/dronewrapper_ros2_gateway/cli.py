"""The drone as ROS 2 topics and services on rmw_zenoh (``dronewrapper ros2``).

The same process as ``python -m dronewrapper_ros2_gateway``, with the same liveliness name
(``{ns}/alive/ros2_gateway``).
"""

from __future__ import annotations

import argparse
from collections.abc import Sequence

from dronewrapper.runtime.service import run_service
from dronewrapper_ros2_gateway.config import Config
from dronewrapper_ros2_gateway.entities import PORTS
from dronewrapper_ros2_gateway.process import run


def _same_name(args: argparse.Namespace, _overrides: list[str]) -> None:
    args.name = args.name or "ros2_gateway"


def main(argv: Sequence[str] | None = None) -> int:
    """Run the gateway (``argv`` without the program name)."""
    return run_service("ros2", __doc__, Config, run, argv, configure=_same_name, ports=PORTS)
