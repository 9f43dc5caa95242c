"""bridge_px4_zenoh: PX4 over its own Zenoh (its ``zenoh`` module, uORB topics in rmw_zenoh's
format) on the MAVROS-equivalent keys, with no MAVLink in between.

Reads ``<domain>/fmu/out/...`` and PX4's liveliness tokens on the router PX4 dials (the
project's), refuses a firmware whose message versions differ (naming topic and hashes), writes
offboard control mode, trajectory setpoints and vehicle commands to ``/fmu/in``, with the
failsafe contract of docs/design.md.
"""

from dronewrapper.runtime.service import run_service
from dronewrapper_bridge_px4_zenoh.config import Config
from dronewrapper_bridge_px4_zenoh.node import PORTS, run


def main(argv: list[str] | None = None) -> int:
    """Entry point (``python -m dronewrapper_bridge_px4_zenoh``)."""
    return run_service("bridge_px4_zenoh", __doc__, Config, run, argv, ports=PORTS)


if __name__ == "__main__":
    raise SystemExit(main())
