"""bridge_mavlink: a PX4 / ArduPilot autopilot over MAVLink on MAVROS-equivalent Zenoh keys.

Connects to the autopilot with a pymavlink URL (``connection``, default udpin:127.0.0.1:14540),
publishes state and telemetry in ENU/FLU, serves arming/takeoff/land/set_mode/param services,
forwards setpoints at >= 20 Hz with the failsafe contract of docs/design.md.
"""

import argparse

from dronewrapper.runtime.service import run_service
from dronewrapper_bridge_mavlink.config import Config
from dronewrapper_bridge_mavlink.node import run


def _add_args(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "--connection",
        metavar="URL",
        help="pymavlink URL: udpin:HOST:PORT, udpout:HOST:PORT, tcp:HOST:PORT, tcpin:HOST:PORT "
        "or a serial device (same as --set connection=URL)",
    )
    parser.add_argument("--baud", type=int, help="serial baud rate (same as --set baud=N)")


def _configure(args: argparse.Namespace, overrides: list[str]) -> None:
    if args.connection:
        overrides.append(f"connection={args.connection}")
    if args.baud:
        overrides.append(f"baud={args.baud}")


def main(argv: list[str] | None = None) -> int:
    """Entry point (``python -m dronewrapper_bridge_mavlink``)."""
    return run_service(
        "bridge_mavlink", __doc__, Config, run, argv, add_args=_add_args, configure=_configure
    )


if __name__ == "__main__":
    raise SystemExit(main())
