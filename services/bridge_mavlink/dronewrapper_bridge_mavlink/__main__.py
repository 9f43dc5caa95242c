"""bridge_mavlink: a PX4 / ArduPilot autopilot over MAVLink on MAVROS-equivalent Zenoh keys.

Connects to the autopilot with a pymavlink URL (``connection``, default udpin:127.0.0.1:14540),
publishes state and telemetry in ENU/FLU, serves the take-off and landing operations and the
arming/takeoff/land/set_mode/param services, forwards setpoints at >= 20 Hz with the failsafe
contract of docs/design.md.
"""

from dronewrapper_bridge_base.shortcuts import bridge_main
from dronewrapper_bridge_mavlink.config import Config
from dronewrapper_bridge_mavlink.flags import SHORTCUTS
from dronewrapper_bridge_mavlink.node import PORTS, run


def main(argv: list[str] | None = None) -> int:
    """Entry point (``python -m dronewrapper_bridge_mavlink``)."""
    return bridge_main("bridge_mavlink", __doc__, Config, run, PORTS, SHORTCUTS, argv)


if __name__ == "__main__":
    raise SystemExit(main())
