"""A Zenoh router as a Python process (no extra binary): ``dronewrapper router``."""

from __future__ import annotations

import logging
import threading

from dronewrapper.runtime.node import open_session
from dronewrapper.runtime.options import DEFAULT_ROUTER, ZenohOptions

log = logging.getLogger("router")


def router_options(
    listen: list[str] | None = None, connect: list[str] | None = None
) -> ZenohOptions:
    """Options for a router listening on ``listen`` (default loopback 7447)."""
    return ZenohOptions(
        mode="router", listen=list(listen or [DEFAULT_ROUTER]), connect=list(connect or [])
    )


def run_router(
    options: ZenohOptions, stop: threading.Event, ready: threading.Event | None = None
) -> None:
    """Run a router until ``stop`` is set, then close it."""
    session = open_session(options)
    try:
        log.info("router %s listening on %s", session.zid(), ", ".join(options.listen))
        if ready is not None:
            ready.set()
        while not stop.wait(0.5):
            pass
    finally:
        session.close()
