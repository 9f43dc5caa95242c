"""bridge_tello: a DJI Tello (SDK 2.0 over UDP) on the MAVROS-equivalent Zenoh keys.

Talks to the Tello at ``tello_address`` (default 192.168.10.1, the Tello's Wi-Fi; a simulated
Tello: 127.0.0.1), publishes state, telemetry (ENU/FLU, position dead-reckoned) and the
decoded frontal camera, serves the take-off and landing operations and arming/takeoff/land/
set_mode/param, flies setpoints with ``rc`` sticks, and keeps the failsafe contract of
docs/design.md.
"""

from dronewrapper_bridge_base.shortcuts import bridge_main
from dronewrapper_bridge_tello.config import Config
from dronewrapper_bridge_tello.flags import SHORTCUTS
from dronewrapper_bridge_tello.node import PORTS, run


def main(argv: list[str] | None = None) -> int:
    """Entry point (``python -m dronewrapper_bridge_tello``)."""
    return bridge_main("bridge_tello", __doc__, Config, run, PORTS, SHORTCUTS, argv)


if __name__ == "__main__":
    raise SystemExit(main())
