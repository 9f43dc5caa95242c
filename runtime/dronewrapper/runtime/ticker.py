"""One thread that ticks many callers at one rate: the shared timer of a process's members.

A bridge ticks its core at a fixed rate (30 Hz) from a thread of its own; N bridges hosted in
one process (:mod:`dronewrapper.runtime.host`) would wake N threads, each taking the
interpreter's lock, 30 times a second for a few microseconds of work each. A :class:`Ticker`
wakes once per period and calls every caller's ``tick`` in turn, in the order they joined:
the same rate for each, one wake-up for all.

What the callers share: a ``tick`` that takes long delays the later callers' ticks of that
period (each caller's tick is short: the bridge's core, a few tens of microseconds); an
exception out of one ``tick`` is logged and counted (``errors``) and the others go on. A
caller leaves when its ``stop`` event is set (it is not called after the period in which the
ticker sees it set). The thread ends when the last caller has left, and a new one starts when
another joins.
"""

from __future__ import annotations

import logging
import threading
from collections.abc import Callable

from dronewrapper.runtime.clock import REAL, Clock
from dronewrapper.runtime.rate import Ratekeeper

log = logging.getLogger("ticker")


class Ticker:
    """Calls each joined ``tick()`` at ``rate_hz`` (on ``clock``), all from one thread.

    Args:
        rate_hz: ticks per second (> 0).
        clock: the clock the period is kept on (the real one unless given).
        name: the thread's name.
    """

    def __init__(self, rate_hz: float, clock: Clock = REAL, name: str = "ticker") -> None:
        if not rate_hz > 0:
            raise ValueError(f"rate must be > 0 Hz, got {rate_hz}")
        self.rate_hz = rate_hz
        self.clock = clock
        self.name = name
        self.errors = 0
        self._lock = threading.Lock()
        self._callers: list[tuple[Callable[[], None], threading.Event]] = []
        self._thread: threading.Thread | None = None

    @property
    def callers(self) -> int:
        """How many callers are ticked now."""
        with self._lock:
            return len(self._callers)

    def join(self, tick: Callable[[], None], stop: threading.Event) -> None:
        """Call ``tick()`` every period from now until ``stop`` is set."""
        with self._lock:
            self._callers.append((tick, stop))
            if self._thread is None:
                self._thread = self.clock.thread(self._run, self.name)
                self._thread.start()

    def tick_all(self) -> bool:
        """One period: every caller whose ``stop`` is not set ticks once, in order; the others
        leave. False when none is left (the thread then ends)."""
        with self._lock:
            self._callers = [(tick, stop) for tick, stop in self._callers if not stop.is_set()]
            callers = list(self._callers)
            if not callers:
                self._thread = None
                return False
        for tick, stop in callers:
            if stop.is_set():
                continue
            try:
                tick()
            except Exception:
                self.errors += 1
                log.exception("%s: a tick failed", self.name)
        return True

    def _run(self) -> None:
        rate = Ratekeeper(self.rate_hz, clock=self.clock)
        while rate.sleep() and self.tick_all():
            pass
