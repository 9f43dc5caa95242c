"""bridge_mavlink's command-line shortcuts: ``--connection URL`` and ``--baud N`` are
``--set connection=URL`` and ``--set baud=N``."""

from __future__ import annotations

import argparse


def add_flags(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "--connection",
        metavar="URL",
        help="pymavlink URL: udpin:HOST:PORT, udpout:HOST:PORT, tcp:HOST:PORT, tcpin:HOST:PORT "
        "or a serial device (same as --set connection=URL)",
    )
    parser.add_argument("--baud", type=int, help="serial baud rate (same as --set baud=N)")


def as_overrides(args: argparse.Namespace, overrides: list[str]) -> None:
    """Append the flags given to ``overrides`` (``key=value``, as ``--set``)."""
    if args.connection:
        overrides.append(f"connection={args.connection}")
    if args.baud:
        overrides.append(f"baud={args.baud}")
