"""bridge_tello: a DJI Tello (SDK 2.0 over UDP) on the MAVROS-equivalent Zenoh keys.

Talks to the Tello at ``tello_address`` (default 192.168.10.1, the Tello's Wi-Fi; a simulated
Tello: 127.0.0.1), publishes state, telemetry (ENU/FLU, position dead-reckoned) and the
decoded frontal camera, serves arming/takeoff/land/set_mode/param, flies setpoints with ``rc``
sticks, and keeps the failsafe contract of docs/design.md.
"""

import argparse

from dronewrapper.runtime.service import run_service
from dronewrapper_bridge_tello.config import Config
from dronewrapper_bridge_tello.node import run


def _add_args(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "--tello", metavar="ADDRESS", help="the Tello's IP address (same as --set tello_address=A)"
    )
    parser.add_argument(
        "--local",
        metavar="ADDRESS",
        help="address our sockets bind (same as --set local_address=A)",
    )


def _configure(args: argparse.Namespace, overrides: list[str]) -> None:
    if args.tello:
        overrides.append(f"tello_address={args.tello}")
    if args.local:
        overrides.append(f"local_address={args.local}")


def main(argv: list[str] | None = None) -> int:
    """Entry point (``python -m dronewrapper_bridge_tello``)."""
    return run_service(
        "bridge_tello", __doc__, Config, run, argv, add_args=_add_args, configure=_configure
    )


if __name__ == "__main__":
    raise SystemExit(main())
