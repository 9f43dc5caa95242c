"""What a test's MAVLink endpoint received, with each message's receive time, and the ways the
tests read it: since a time, the newest of a type, the first matching one (waited for), the
STATUSTEXTs. The endpoint appends under :attr:`MessageLog.lock` (its reader may be a thread)
and says how to wait (:meth:`MessageLog.wait_until`: real time, or a virtual clock's).
"""

from __future__ import annotations

import threading
from collections.abc import Callable
from typing import Any


class MessageLog:
    """``log``: (receive time s, message), in the order received."""

    def __init__(self) -> None:
        self.log: list[tuple[float, Any]] = []
        self.lock = threading.Lock()

    def wait_until(self, found: Callable[[], Any], timeout: float, what: str) -> Any:
        """Wait until ``found()`` is truthy (at most ``timeout`` s) and return it."""
        raise NotImplementedError

    def since(self, t0: float, kind: str | None = None) -> list:
        return [m for _, m in self.timed(t0, kind)]

    def timed(self, t0: float, kind: str | None = None) -> list[tuple[float, Any]]:
        """(receive time, message) pairs received at or after ``t0``."""
        with self.lock:
            return [
                (t, m) for t, m in self.log if t >= t0 and (kind is None or m.get_type() == kind)
            ]

    def latest(self, kind: str) -> Any:
        with self.lock:
            return next((m for _, m in reversed(self.log) if m.get_type() == kind), None)

    def wait_msg(self, kind: str, pred=lambda m: True, timeout: float = 10.0, t0: float = 0.0):
        """The first ``kind`` message received since ``t0`` that ``pred`` accepts (waited for)."""

        def found():
            return next((m for m in self.since(t0, kind) if pred(m)), None)

        return self.wait_until(found, timeout, f"{kind} matching {pred}")

    def texts(self, t0: float = 0.0) -> list[str]:
        return [m.text for m in self.since(t0, "STATUSTEXT")]
