"""ROS 2 gateway: presents drones' keys as ROS 2 (rmw_zenoh) topics and services, both ways.

Telemetry and images go out as MAVROS 2's topics; setpoints and service calls come in and go to
the bridge as one more commander (same validation, command lease and failsafe as the SDK's).
"""

from dronewrapper.runtime.service import run_service
from dronewrapper_ros2_gateway.config import Config
from dronewrapper_ros2_gateway.entities import PORTS
from dronewrapper_ros2_gateway.process import run


def main(argv: list[str] | None = None) -> int:
    """Entry point (``python -m dronewrapper_ros2_gateway``; a member of a hosting process)."""
    return run_service("ros2_gateway", __doc__, Config, run, argv, ports=PORTS)


if __name__ == "__main__":
    raise SystemExit(main())
