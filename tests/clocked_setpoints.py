"""A test's commander on a fake bus: the newest setpoint re-published at 20 Hz of the node's
clock, from a worker thread of that clock, so it streams on while the test's thread is in a
service call (as an app's stream does) and every setpoint is sent at an exact virtual time."""

from __future__ import annotations

import threading

import msgspec

from dronewrapper.msgs import registry
from dronewrapper.msgs.mavros import PositionTarget
from dronewrapper.msgs.std import Header
from dronewrapper.runtime.fake import FakeNode

PERIOD_S = 0.05
"""Time between two publications of the same target (s): 20 Hz, the SDK's stream rate."""


class ClockedSetpoints:
    """``node``'s setpoint stream; ``target`` None sends nothing; ``sent``: the clock's Unix
    time of each setpoint published (each is stamped with it too)."""

    def __init__(self, node: FakeNode) -> None:
        self.clock = node.clock
        self.setpoints = node.publisher(registry.SETPOINT_RAW_LOCAL)
        self.target: PositionTarget | None = None
        self.sent: list[float] = []
        self._stop = threading.Event()
        self._thread = self.clock.thread(self._stream, "commander")
        self._thread.start()

    def _stream(self) -> None:
        while not self.clock.wait(self._stop, PERIOD_S):
            if self.target is not None:
                self._put(self.target)

    def _put(self, target: PositionTarget) -> None:
        now = self.clock.time()
        self.sent.append(now)
        self.setpoints.put(msgspec.structs.replace(target, header=Header(stamp=now)))

    def command(self, target: PositionTarget | None) -> None:
        """Stream ``target`` from now on (published at once), or stop sending (``None``)."""
        self.target = target
        if target is not None:
            self._put(target)

    def close(self) -> None:
        self._stop.set()
        self._thread.join(10.0)
