"""Inputs read as "latest value + age": what every actuating loop consumes.

A subscriber callback calls :meth:`Latest.update`; loops read :meth:`Latest.fresh` so a stale
input never drives an actuator. The same holder is the newest-frame policy of a slow consumer
(perception, the station's video senders): :meth:`Latest.take` returns the newest item with its
number, so the reader knows exactly how many it skipped; ``update(..., wait_taken=stop)`` is a
lossless hand-over instead (a camera reading a file); :meth:`Latest.listen` tells a consumer on
another loop (asyncio, a web socket) that a value came.

Ages and waits are on the holder's :class:`~dronewrapper.runtime.clock.Clock` (the node's), so
a holder under a :class:`~dronewrapper.runtime.clock.VirtualClock` waits in virtual time.
"""

from __future__ import annotations

import math
import threading
from collections.abc import Callable
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
        self._taken = True
        self._listeners: list[Callable[[], None]] = []
        self.count = 0

    def update(self, value: T, *, wait_taken: threading.Event | None = None) -> None:
        """Store a new value, stamped with the receive time, and tell the listeners.

        With ``wait_taken`` (a stop event), first wait until the previous value was taken
        (:meth:`take`) or the event is set: a lossless hand-over.
        """
        with self._cond:
            while wait_taken is not None and not self._taken and not wait_taken.is_set():
                self.clock.wait_for(self._cond, lambda: self._taken or wait_taken.is_set(), 0.1)
            self._value = value
            self._received_at = self.clock.monotonic()
            self._taken = False
            self.count += 1
            self._cond.notify_all()
            listeners = list(self._listeners)
        for notify in listeners:
            notify()

    def listen(self, notify: Callable[[], None]) -> None:
        """Call ``notify()`` after every update, on the updating thread (keep it short)."""
        with self._cond:
            self._listeners.append(notify)

    def unlisten(self, notify: Callable[[], None]) -> None:
        with self._cond:
            if notify in self._listeners:
                self._listeners.remove(notify)

    @property
    def received_at(self) -> float:
        """When the newest value arrived (clock's monotonic s; -inf before the first)."""
        return self._received_at

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
            self._taken = True
            self._cond.notify_all()
            return self.count, self._value  # type: ignore[return-value]
