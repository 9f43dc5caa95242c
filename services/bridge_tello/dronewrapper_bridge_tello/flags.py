"""bridge_tello's command-line shortcuts: ``--tello ADDRESS`` and ``--local ADDRESS`` are
``--set tello_address=ADDRESS`` and ``--set local_address=ADDRESS``."""

from __future__ import annotations

import argparse


def add_flags(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "--tello", metavar="ADDRESS", help="the Tello's IP address (same as --set tello_address=A)"
    )
    parser.add_argument(
        "--local",
        metavar="ADDRESS",
        help="address our sockets bind (same as --set local_address=A)",
    )


def as_overrides(args: argparse.Namespace, overrides: list[str]) -> None:
    """Append the flags given to ``overrides`` (``key=value``, as ``--set``)."""
    if args.tello:
        overrides.append(f"tello_address={args.tello}")
    if args.local:
        overrides.append(f"local_address={args.local}")
