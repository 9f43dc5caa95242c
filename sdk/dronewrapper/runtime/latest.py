"""Inputs read as "latest value + age": what every actuating loop consumes.

A subscriber callback calls :meth:`Latest.update`; loops read :meth:`Latest.fresh` so a stale
input never drives an actuator. The same holder is the newest-frame policy of a slow consumer
(perception, a camera's lossless hand-over): :meth:`Latest.take` returns the newest item with its
number, so the reader knows exactly how many it skipped.

Ages and waits are on the holder's :class:`~dronewrapper.runtime.clock.Clock` (the node's), so
a holder under a :class:`~dronewrapper.runtime.clock.VirtualClock` waits in virtual time.
"""

from __future__ import annotations

import math
import threading
from typing import Generic, TypeVar

from dronewrapper.runtime.clock import REAL, Clock

T = TypeVar("T")


class Latest(Generic[T]):
    """The newest value of an input, when it arrived, and how many arrived.

    Thread-safe: written from a callback thread, read from any thread. Time is ``clock``'s
    monotonic time, in seconds.
    """

    def __init__(self, name: str = "", clock: Clock = REAL) -> None:
        self.name = name
        self.clock = clock
        self._cond = threading.Condition()
        self._value: T | None = None
        self._received_at = -math.inf
        self.count = 0

    def update(self, value: T) -> None:
        """Store a new value, stamped with the receive time."""
        with self._cond:
            self._value = value
            self._received_at = self.clock.monotonic()
            self.count += 1
            self._cond.notify_all()

    @property
    def value(self) -> T | None:
        """The newest value, however old (None before the first)."""
        return self._value

    def age(self) -> float:
        """Seconds since the newest value arrived (inf before the first)."""
        return self.clock.monotonic() - self._received_at

    def fresh(self, max_age: float) -> T | None:
        """The newest value if it is at most ``max_age`` seconds old, else None."""
        with self._cond:
            if self._value is None or self.clock.monotonic() - self._received_at > max_age:
                return None
            return self._value

    def wait(self, timeout: float, *, newer_than: int | None = None) -> T:
        """Block until a value is present (or one newer than count ``newer_than``).

        Raises:
            TimeoutError: nothing arrived within ``timeout`` seconds.
        """
        floor = 0 if newer_than is None else newer_than
        with self._cond:
            if not self.clock.wait_for(self._cond, lambda: self.count > floor, max(0.0, timeout)):
                raise TimeoutError(f"no {self.name or 'input'} within {timeout:g} s")
            return self._value  # type: ignore[return-value]

    def take(self, timeout: float, newer_than: int) -> tuple[int, T] | None:
        """Wait up to ``timeout`` s for a value whose number is above ``newer_than``.

        Returns:
            (its number, the value) read atomically, or None on timeout. Numbers start at 1.
        """
        with self._cond:
            if not self.clock.wait_for(
                self._cond, lambda: self.count > newer_than, max(0.0, timeout)
            ):
                return None
            return self.count, self._value  # type: ignore[return-value]
