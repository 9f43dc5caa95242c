"""Controller: follows a colour blob or a person with three PIDs (vx, vz, yaw rate).

Subscribes {ns}/perception/detections, commands the aircraft with the SDK's ``DroneClient``
(setpoints on {ns}/mavros/setpoint_raw/local) and publishes {ns}/controller/status.
"""

from dronewrapper.runtime.service import run_service
from dronewrapper_controller.config import Config
from dronewrapper_controller.node import PORTS, run


def main(argv: list[str] | None = None) -> int:
    """Entry point (``python -m dronewrapper_controller``)."""
    return run_service("controller", __doc__, Config, run, argv, ports=PORTS)


if __name__ == "__main__":
    raise SystemExit(main())
