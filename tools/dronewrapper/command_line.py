"""What the ``dronewrapper`` tool's commands share: a client session with the router their
arguments name, and a stop event that SIGINT and SIGTERM set."""

from __future__ import annotations

import argparse
import signal
import sys
import threading
from typing import TYPE_CHECKING

from dronewrapper.runtime.options import options_from_args

if TYPE_CHECKING:
    import zenoh


def client_session(args: argparse.Namespace, prog: str) -> zenoh.Session | None:
    """A client session with the router the parsed ``args`` name, or None: why not printed
    to stderr after ``prog`` (the command, e.g. ``dronewrapper echo``)."""
    from dronewrapper.router_reach import open_client_session

    try:
        return open_client_session(options_from_args(args))
    except ConnectionError as exc:
        print(f"{prog}: {exc}", file=sys.stderr)
        return None


def stop_on_signals() -> threading.Event:
    """An event that SIGINT and SIGTERM set (instead of raising), for a command's loop."""
    stop = threading.Event()
    for sig in (signal.SIGINT, signal.SIGTERM):
        signal.signal(sig, lambda *_: stop.set())
    return stop
