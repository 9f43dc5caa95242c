"""Time a threaded service reads and waits on, injectable: the real clocks or virtual time.

A service takes a :class:`Clock` (default :data:`REAL`) and reads and waits only through it:
``monotonic()`` for intervals and deadlines, ``time()`` for stamps (Unix time), ``sleep``,
``wait(event, timeout)`` for ``Event.wait``, ``wait_for(cond, predicate, timeout)`` for
``Condition.wait_for``, and ``thread(target, name)`` for its threads (whose ``join`` counts in
the same time). Calling the clock gives ``monotonic()``, so it also fits where a plain
``clock: Callable[[], float]`` is expected (``Latest``, ``FakeBus``). All times in seconds.

:class:`VirtualClock` runs such a service, threads and all, in virtual time: time stands still
while any of its threads works, and when every one of them waits it jumps to the earliest
deadline among their waits and wakes that waiter alone (deadline order, then first come). It is
a discrete-event simulation whose events are the threads' own waits, so what the service does
in time (pacing, timeouts, backoff, periods, stamps) comes out exact, however loaded the
machine. The test drives it from its own thread::

    clock = VirtualClock()
    worker = clock.thread(service.run, "service")
    worker.start()
    clock.run_until(lambda: service.frames >= 30, within=5.0, what="30 frames")

A thread of the service must wait only through the clock (a wait elsewhere, e.g. a plain
``time.sleep``, counts as work: time does not move meanwhile).

The same clock serves stepped use, where the test's own thread is the service (the fake bus,
a DroneWrapper's blocking calls): a wait on a thread that is not one of its workers drives
time itself, up to the wait's deadline or its condition. With a :attr:`VirtualClock.stepper`
(``stepper(until, done)``, e.g. the fake bus delivering its scheduled messages and ticking a
simulated aircraft), that stepper moves time; without one the workers run as in
:meth:`VirtualClock.run_until`. :meth:`VirtualClock.advance_to` lets the workers do what is due
on the way, in deadline order.
"""

from __future__ import annotations

import itertools
import math
import threading
import time as _time
from collections.abc import Callable
from dataclasses import dataclass

POLL_S = 0.005
"""Real seconds between a waiting thread's checks of its condition, for conditions changed
without a notification through the clock (an event set by the test, a slot filled)."""


class Clock:
    """The real clocks (what a service uses unless a test gives it another)."""

    def __call__(self) -> float:
        return self.monotonic()

    def monotonic(self) -> float:
        return _time.monotonic()

    def time(self) -> float:
        """Unix time (s)."""
        return _time.time()

    def sleep(self, seconds: float) -> None:
        _time.sleep(max(0.0, seconds))

    def wait(self, event: threading.Event, timeout: float) -> bool:
        """Wait up to ``timeout`` s for ``event``; True if it is set (as ``Event.wait``)."""
        return event.wait(max(0.0, timeout))

    def wait_for(
        self, cond: threading.Condition, predicate: Callable[[], bool], timeout: float | None
    ) -> bool:
        """With ``cond`` held (once): wait until ``predicate()`` or ``timeout`` s (None: no
        end), ``cond`` released meanwhile; the predicate's last value (as
        ``Condition.wait_for``)."""
        return cond.wait_for(predicate, timeout)

    def thread(self, target: Callable[[], object], name: str) -> threading.Thread:
        """A daemon thread running ``target`` (not started)."""
        return threading.Thread(target=target, name=name, daemon=True)


REAL = Clock()


@dataclass(eq=False)
class _Waiter:
    predicate: Callable[[], bool]
    deadline: float
    order: int
    wake: threading.Condition
    """Its own condition on the clock's lock: a wake-up reaches this waiter alone."""
    released: bool = False


class VirtualClock(Clock):
    """Virtual time for a threaded service under test (see the module doc).

    ``monotonic`` starts at ``monotonic`` and ``time()`` at ``time`` (defaults: fixed values,
    so runs repeat exactly); both move together, only when every thread made by
    :meth:`thread` waits.
    """

    def __init__(self, monotonic: float = 1000.0, time: float | None = None) -> None:
        self._now = monotonic
        self._offset = (1.8e9 if time is None else time) - monotonic
        self._lock = threading.Lock()
        self._cv = threading.Condition(self._lock)  # the driving threads wait on it
        self._waiters: dict[threading.Thread, _Waiter] = {}
        self._workers: set[threading.Thread] = set()
        self._order = itertools.count()
        self.stepper: Callable[[float, Callable[[], bool]], object] | None = None
        """``stepper(until, done)``: moves time to ``until`` or until ``done()`` for a wait on
        the driving thread (stepped use); None: the workers run, as in :meth:`run_until`."""

    def monotonic(self) -> float:
        return self._now

    def time(self) -> float:
        return self._now + self._offset

    def advance_to(self, t: float) -> None:
        """Move to ``t`` (never back), the workers doing what falls due on the way (deadline
        order); from the driving thread only."""
        driving = threading.current_thread() not in self._workers
        if driving and self._workers and self._run(lambda: False, t, 60.0) == "busy":
            raise AssertionError("virtual clock: workers still busy after 60 s (real)")
        with self._cv:
            self._now = max(self._now, t)
            self._notify_all()

    def sleep(self, seconds: float) -> None:
        self._wait(lambda: False, seconds)

    def wait(self, event: threading.Event, timeout: float) -> bool:
        return self._wait(event.is_set, timeout)

    def wait_for(
        self, cond: threading.Condition, predicate: Callable[[], bool], timeout: float | None
    ) -> bool:
        if predicate():
            return True
        cond.release()
        try:
            self._wait(predicate, timeout)
        finally:
            cond.acquire()
        return predicate()

    def thread(self, target: Callable[[], object], name: str) -> threading.Thread:
        return _Worker(self, target, name)

    def _wait(self, predicate: Callable[[], bool], timeout: float | None) -> bool:
        """Wait until ``predicate()`` or until the driver wakes this waiter at its deadline
        (on the driving thread: drive time there, see the module doc)."""
        if predicate():
            return True
        if timeout is not None and timeout <= 0:
            return False
        me = threading.current_thread()
        if me not in self._workers:
            return self._drive(predicate, timeout)
        with self._cv:
            deadline = math.inf if timeout is None else self._now + timeout
            wake = threading.Condition(self._lock)
            waiter = _Waiter(predicate, deadline, next(self._order), wake)
            self._waiters[me] = waiter
            self._cv.notify_all()  # the driver may find everything waiting now
            self._settled()  # and what this thread did may let others go on
            try:
                while not waiter.released and not predicate():
                    wake.wait(POLL_S)
            finally:
                del self._waiters[me]
        return predicate()

    def _notify_all(self) -> None:
        """Wake every waiter and driver to look at its condition again (under ``_cv``)."""
        self._cv.notify_all()
        for waiter in self._waiters.values():
            waiter.wake.notify()

    # ---- the driver (the test's thread) ----

    def _drive(self, predicate: Callable[[], bool], timeout: float | None) -> bool:
        """A wait on the driving thread: move time until ``predicate()`` or the deadline."""
        if timeout is None:
            raise AssertionError("virtual clock: a wait without end on the driving thread")
        until = self._now + timeout
        if self.stepper is not None:
            self.stepper(until, predicate)
        elif self._run(predicate, until, 60.0) == "busy":
            raise AssertionError("virtual clock: workers still busy after 60 s (real)")
        if not predicate():
            self.advance_to(until)
        return predicate()

    def _settled(self) -> bool:
        """Every worker waits, and no waiter can go on before time moves (under ``_cv``);
        a waiter found able to go on is woken (what other threads did while it waited, e.g.
        an event set, reaches it now rather than at its next poll)."""
        settled = True
        for waiter in self._waiters.values():
            if waiter.released:
                settled = False
            elif waiter.predicate():
                settled = False
                waiter.wake.notify()
        return settled and self._workers <= self._waiters.keys()

    def run_until(
        self, done: Callable[[], object], within: float, what: str = "", real_timeout: float = 60
    ) -> None:
        """Let the workers run, moving time, until ``done()`` is true at a moment when they all
        wait (so what it reads is settled).

        Raises:
            AssertionError: not done within ``within`` s of virtual time, nothing left that
                could happen (every worker ended or waits without end), or the workers still
                busy after ``real_timeout`` real seconds (each naming ``what``).
        """
        what = what or str(done)
        outcome = self._run(done, self._now + within, real_timeout)
        if outcome == "limit":
            raise AssertionError(f"not within {within:g} s (virtual): {what}")
        if outcome == "never":
            raise AssertionError(f"nothing left to happen, never: {what}")
        if outcome == "busy":
            raise AssertionError(f"still busy after {real_timeout:g} s (real): {what}")

    def run_for(self, seconds: float, real_timeout: float = 60) -> None:
        """Let the workers run for ``seconds`` of virtual time (the clock ends ``seconds``
        later, whatever they do)."""
        end = self._now + seconds
        if self._run(lambda: False, end, real_timeout) == "busy":
            raise AssertionError(f"still busy after {real_timeout:g} s (real)")
        self.advance_to(end)

    def _run(self, done: Callable[[], object], limit: float, real_timeout: float) -> str:
        """Wake waiters in deadline order up to ``limit``; ``done``, ``limit``, ``never``
        (nothing can happen any more) or ``busy`` (the workers never all waited)."""
        assert threading.current_thread() not in self._workers, "driven from a worker"
        give_up = _time.monotonic() + real_timeout
        while True:
            with self._cv:
                while not self._settled():
                    if _time.monotonic() > give_up:
                        return "busy"
                    self._cv.wait(POLL_S)
            if done():
                return "done"
            with self._cv:
                if not self._settled():
                    continue
                first = min(
                    self._waiters.values(), key=lambda w: (w.deadline, w.order), default=None
                )
                if first is None or first.deadline == math.inf:
                    return "never"
                if first.deadline > limit:
                    self._now = max(self._now, limit)
                    return "limit"
                self._now = max(self._now, first.deadline)
                first.released = True
                first.wake.notify()


class _Worker(threading.Thread):
    """A thread of a service under a :class:`VirtualClock`: counted from ``start``, alive
    until its target has returned (``finished``), its ``join`` from another worker in virtual
    time."""

    def __init__(self, clock: VirtualClock, target: Callable[[], object], name: str) -> None:
        super().__init__(target=target, name=name, daemon=True)
        self._clock = clock
        self.finished = False

    def start(self) -> None:
        with self._clock._cv:
            self._clock._workers.add(self)
        try:
            super().start()
        except BaseException:
            with self._clock._cv:
                self._clock._workers.discard(self)
            raise

    def run(self) -> None:
        try:
            super().run()
        finally:
            with self._clock._cv:
                self.finished = True
                self._clock._workers.discard(self)
                self._clock._notify_all()

    def is_alive(self) -> bool:
        return not self.finished and super().is_alive()

    def join(self, timeout: float | None = None) -> None:
        if threading.current_thread() in self._clock._workers:
            if not self._clock._wait(lambda: self.finished, timeout):
                return
            timeout = None  # finished: only the thread's own exit is left
        super().join(timeout)
