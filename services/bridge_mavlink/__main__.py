"""bridge_mavlink: a PX4 / ArduPilot autopilot over MAVLink on MAVROS-equivalent Zenoh keys.

Connects to the autopilot with a pymavlink URL (``connection``, default udpin:0.0.0.0:14540),
publishes state and telemetry in ENU/FLU, serves arming/takeoff/land/set_mode/param services,
forwards setpoints at >= 20 Hz with the failsafe contract of DESIGN.md.
"""

from dronewrapper.runtime.service import run_service
from dronewrapper_bridge_mavlink.node import Config, run


def main(argv: list[str] | None = None) -> int:
    """Entry point (``python -m dronewrapper_bridge_mavlink``)."""
    return run_service("bridge_mavlink", __doc__, Config, run, argv)


if __name__ == "__main__":
    raise SystemExit(main())
