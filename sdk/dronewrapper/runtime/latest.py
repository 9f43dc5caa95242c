"""Inputs read as "latest value + age": what every actuating loop consumes.

A subscriber callback calls :meth:`Latest.update`; loops read :meth:`Latest.fresh` so a stale
input never drives an actuator. The same slot is the newest-frame policy of a slow consumer
(perception): :meth:`Latest.take` returns the newest item with its number, so the reader knows
exactly how many it skipped.
"""

from __future__ import annotations

import math
import threading
import time
from collections.abc import Callable
from typing import Generic, TypeVar

T = TypeVar("T")


class Latest(Generic[T]):
    """The newest value of an input, when it arrived, and how many arrived.

    Thread-safe: written from a Zenoh callback thread, read from any thread. Time is the
    monotonic clock (``clock``, injectable for tests), in seconds.
    """

    def __init__(self, name: str = "", clock: Callable[[], float] = time.monotonic) -> None:
        self.name = name
        self._clock = clock
        self._cond = threading.Condition()
        self._value: T | None = None
        self._received_at = -math.inf
        self.count = 0

    def update(self, value: T) -> None:
        """Store a new value, stamped with the receive time."""
        with self._cond:
            self._value = value
            self._received_at = self._clock()
            self.count += 1
            self._cond.notify_all()

    @property
    def value(self) -> T | None:
        """The newest value, however old (None before the first)."""
        return self._value

    def age(self) -> float:
        """Seconds since the newest value arrived (inf before the first)."""
        return self._clock() - self._received_at

    def fresh(self, max_age: float) -> T | None:
        """The newest value if it is at most ``max_age`` seconds old, else None."""
        with self._cond:
            if self._value is None or self._clock() - self._received_at > max_age:
                return None
            return self._value

    def wait(self, timeout: float, *, newer_than: int | None = None) -> T:
        """Block until a value is present (or one newer than count ``newer_than``).

        Raises:
            TimeoutError: nothing arrived within ``timeout`` seconds.
        """
        deadline = time.monotonic() + timeout
        with self._cond:
            while self._value is None or (newer_than is not None and self.count <= newer_than):
                remaining = deadline - time.monotonic()
                if remaining <= 0:
                    what = self.name or "input"
                    raise TimeoutError(f"no {what} within {timeout:g} s")
                self._cond.wait(remaining)
            return self._value  # type: ignore[return-value]

    def take(self, timeout: float, newer_than: int) -> tuple[int, T] | None:
        """Wait up to ``timeout`` s for a value whose number is above ``newer_than``.

        Returns:
            (its number, the value) read atomically, or None on timeout. Numbers start at 1.
        """
        deadline = time.monotonic() + timeout
        with self._cond:
            while self.count <= newer_than:
                remaining = deadline - time.monotonic()
                if remaining <= 0:
                    return None
                self._cond.wait(remaining)
            return self.count, self._value  # type: ignore[return-value]
