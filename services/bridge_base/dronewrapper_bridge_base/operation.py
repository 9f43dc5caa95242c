"""A service call that waits on an aircraft, as a generator a bridge's pure core resumes.

An operation's generator queues what it sends on its core and yields the time (monotonic s) at
which it wants to be resumed at the latest; the core resumes it whenever a message, a reply or a
tick arrives, so every wait re-checks its condition. Its return value is the service reply; an
exception it raises (``ValueError`` for a bad request, ``ServiceError``) is the call's error.
Both bridges' cores (bridge_mavlink, bridge_tello) run their calls this way; the node only
waits on :attr:`Operation.done`.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Generator
from typing import Any

from dronewrapper.runtime.errors import ServiceError

Steps = Generator[float, None, Any]
"""An operation's body: yields wake-up times (monotonic s), returns the reply."""


class Operation:
    """One running operation: :meth:`step` resumes it; ``reply`` or ``error`` once done.

    ``background``: started by the bridge itself (a failsafe landing, a reconnection), so
    nobody waits for it and its error is only logged.
    """

    def __init__(self, steps: Steps, *, background: bool = False) -> None:
        self._steps = steps
        self.name = getattr(steps, "__name__", "operation")
        self.background = background
        self.done = False
        self.reply: Any = None
        self.error: BaseException | None = None
        self.wake_at = -math.inf  # when it asked to be resumed at the latest

    def step(self) -> None:
        """Run until its next wait (or its end)."""
        if self.done:
            return
        try:
            self.wake_at = next(self._steps)
        except StopIteration as stop:
            self.done, self.reply = True, stop.value
        except Exception as exc:  # the call's error (ValueError: a bad request)
            self.done, self.error = True, exc

    def cancel(self) -> None:
        """Stop it where it waits (its cleanup runs: a command slot is released)."""
        self._steps.close()
        if not self.done:
            self.done, self.error = True, ServiceError("the bridge is stopping", "unavailable")

    def interrupt(self, reply: Any) -> None:
        """End it now with ``reply`` (a cancel): its cleanup runs (a command slot is released)."""
        self._steps.close()
        self.done, self.reply, self.error = True, reply, None

    def result(self) -> Any:
        """The reply; raises the operation's error."""
        if self.error is not None:
            raise self.error
        return self.reply


class Operations:
    """A pure core's running operations: started, resumed together, pruned when done.

    ``finished`` counts the operations ended so far: a node that feeds the core notices an
    ending by this count changing, and wakes the service calls waiting on them.
    """

    def __init__(self, log: logging.Logger) -> None:
        self.pending: list[Operation] = []
        self.finished = 0
        self._log = log

    def __len__(self) -> int:
        return len(self.pending)

    def start(self, steps: Steps, *, background: bool = False) -> Operation:
        """Begin an operation: its first step runs now (a bad request fails it at once)."""
        op = Operation(steps, background=background)
        self.pending.append(op)
        op.step()
        self._prune()
        return op

    def advance(self) -> None:
        """Resume every pending operation once (the core has moved its time on)."""
        for op in list(self.pending):
            op.step()
        self._prune()

    def cancel(self, op: Operation) -> None:
        """Abandon ``op`` (the node is stopping): its cleanup runs."""
        op.cancel()
        self._prune()

    def interrupt(self, op: Operation, reply: Any) -> None:
        """End ``op`` now with ``reply`` (a cancel): its cleanup runs."""
        op.interrupt(reply)
        self._prune()

    def _prune(self) -> None:
        for op in [op for op in self.pending if op.done]:
            self.pending.remove(op)
            self.finished += 1
            if op.error is not None and op.background:
                self._log.error("%s failed: %s", op.name, op.error)
