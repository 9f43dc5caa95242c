"""The thin node's half of a pure bridge core: feed it under one lock, execute its effects.

A bridge's core (bridge_mavlink's ``BridgeCore``, bridge_tello's ``TelloCore``) takes inputs
with the time as arguments and queues what to send and publish in an outbox. :class:`CoreDriver`
is the only place a node touches it: every input goes through :meth:`CoreDriver.feed` (the core
called under the lock with the monotonic and wall-clock time, its outbox executed after the lock
is released), and a service call runs its operation to the end with :meth:`CoreDriver.call`,
waiting on the lock's condition until the operation ends, asks to be resumed, or the node stops.
"""

from __future__ import annotations

import threading
import time
from collections.abc import Callable
from typing import Any, Generic, Protocol, TypeVar

from dronewrapper.runtime.operation import Operation, Operations, Steps

MAX_WAIT_S = 0.05
"""A waiting service call looks at its operation at least this often (s)."""


class PureCore(Protocol):
    """What a bridge core offers its driver (time passed in: monotonic s, Unix s)."""

    operations: Operations

    def take(self) -> Any: ...  # the effects queued since the last call
    def start(self, steps: Steps, now: float, stamp: float) -> Operation: ...
    def advance(self, now: float, stamp: float) -> None: ...
    def cancel(self, op: Operation) -> None: ...


C = TypeVar("C", bound=PureCore)


class CoreDriver(Generic[C]):
    """Feeds ``core`` under one lock and hands its outboxes to ``execute`` outside the lock.

    Args:
        core: the pure core.
        execute: carries out one outbox (sends, publications); runs on the feeding thread.
        stop: set when the node stops; a waiting service call then cancels its operation.
        clock, wall: monotonic and Unix time (s), injectable.
    """

    def __init__(
        self,
        core: C,
        execute: Callable[[Any], None],
        stop: threading.Event,
        *,
        clock: Callable[[], float] = time.monotonic,
        wall: Callable[[], float] = time.time,
    ) -> None:
        self.core = core
        self.cond = threading.Condition()  # guards the core; notified when an operation ends
        self._execute = execute
        self._stop = stop
        self._clock = clock
        self._wall = wall

    def feed(self, call: Callable[..., Any], *args: Any) -> Any:
        """Run ``call(*args, now, stamp)`` on the core under the lock, then execute its outbox;
        service calls waiting on their operations are woken when one has finished."""
        with self.cond:
            finished = self.core.operations.finished
            result = call(*args, self._clock(), self._wall())
            out = self.core.take()
            if self.core.operations.finished != finished:
                self.cond.notify_all()
        self._execute(out)
        return result

    def call(self, steps: Steps) -> Any:
        """Start an operation and wait (bounded by its own timeouts) for its reply; raises its
        error. If the node stops meanwhile the operation is cancelled."""
        op = self.feed(self.core.start, steps)
        while not op.done:
            if self._stop.is_set():
                with self.cond:
                    self.core.cancel(op)
                break
            with self.cond:
                if op.done:  # ended by another thread's input (checked under the lock)
                    break
                wait = op.wake_at - self._clock()
                self.cond.wait(min(max(wait, 0.001), MAX_WAIT_S))
            self.feed(self.core.advance)
        return op.result()
