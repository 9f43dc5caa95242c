"""``dronewrapper ros2``: the ROS 2 gateway (the same process as ``python -m
dronewrapper_ros2_gateway``): drones' keys as ROS 2 topics and services over rmw_zenoh."""

from __future__ import annotations

from collections.abc import Sequence

from dronewrapper.runtime.service import run_service
from dronewrapper_ros2_gateway.config import Config
from dronewrapper_ros2_gateway.node import run


def main(argv: Sequence[str] | None = None) -> int:
    """Run the gateway (``argv`` without the program name)."""
    return run_service("ros2", __doc__, Config, run, argv)
