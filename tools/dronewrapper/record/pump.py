"""Samples off the bus through a bounded queue to the caller's thread: the loop the recorder
(:mod:`.capture`) and the live Foxglove server (:mod:`.live`) share. Zenoh's callback only
queues a sample (``(key, payload, receive time ns)``); the caller's thread hands each on, so a
slow writer or viewer never holds up the bus.
"""

from __future__ import annotations

import queue
import threading
import time
from collections.abc import Callable, Sequence

import zenoh

Queued = tuple[str, bytes, int]
"""A queued sample: its key, its payload and its receive time (wall clock, ns since the epoch)."""


def pump(
    session: zenoh.Session,
    keyexprs: Sequence[str],
    on_sample: Callable[[zenoh.Sample], None],
    samples: queue.Queue[Queued],
    handle: Callable[[str, bytes, int], None],
    stop: threading.Event,
    duration: float = 0.0,
) -> None:
    """Subscribe ``on_sample`` (which queues into ``samples``) to every key expression, and
    hand each queued sample to ``handle(key, payload, log_ns)`` until ``stop`` is set or
    ``duration`` s have passed (0: no limit); the subscribers are undeclared on the way out."""
    subscribers = [session.declare_subscriber(k, on_sample) for k in keyexprs]
    deadline = time.monotonic() + duration if duration > 0 else float("inf")
    try:
        while not stop.is_set() and time.monotonic() < deadline:
            try:
                key, payload, log_ns = samples.get(timeout=0.1)
            except queue.Empty:
                continue
            handle(key, payload, log_ns)
    finally:
        for sub in subscribers:
            sub.undeclare()
