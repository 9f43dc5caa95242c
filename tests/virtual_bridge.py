"""A bridge started on a fake bus with the app's node facing it, in virtual time: the frame of
the service tier's flight tests (tests/service/test_*_flight_virtual.py).

A rig makes its simulated aircraft's link on :attr:`VirtualBridge.node`, then hands its bridge
to :meth:`VirtualBridge.start`. Every wait is the bus's virtual time, exact however loaded the
machine.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from clocked_setpoints import ClockedSetpoints

from dronewrapper.msgs import registry
from dronewrapper.msgs.mavros import PositionTarget
from dronewrapper.runtime.fake import FakeBus, FakeNode

T0 = 1_700_000_000.0
"""The bus's start (monotonic and Unix s alike)."""


class VirtualBridge:
    """``node``: the bridge's; ``user``: the app's, with the newest State, ExtendedState and
    local pose, every State, and (once started) a 20 Hz setpoint stream of the node's clock
    (tests/clocked_setpoints.py)."""

    CALL_TIMEOUT_S = 30.0
    """How long a service call may take (virtual s)."""

    def __init__(self) -> None:
        self.bus = FakeBus(start=T0)
        self.clock = self.bus.clock
        self.node = FakeNode("bridge", self.bus)
        self.user = FakeNode("apps", self.bus)
        self.state = self.user.latest(registry.STATE)
        self.ext = self.user.latest(registry.EXTENDED_STATE)
        self.pose = self.user.latest(registry.LOCAL_POSE)
        self.states: list = []
        self.user.subscribe(registry.STATE, self.states.append)

    def start(self, bridge: Any) -> None:
        """Start ``bridge`` (made on :attr:`node`) and the app's setpoint stream."""
        self.bridge = bridge
        self.stream = ClockedSetpoints(self.user)
        self.threads = bridge.start()

    def close(self) -> None:
        """Stop the stream and the bridge; every thread of the bridge has ended."""
        self.stream.close()
        self.node.stop()
        for thread in self.threads:
            thread.join(10.0)
        assert not any(thread.is_alive() for thread in self.threads)

    def alive(self) -> bool:
        return all(thread.is_alive() for thread in self.threads)

    def command(self, target: PositionTarget | None) -> None:
        """Stream ``target`` at 20 Hz from now on, or stop sending (``None``)."""
        self.stream.command(target)

    def call(self, service: Any, request: Any) -> Any:
        return self.user.call(service, request, timeout=self.CALL_TIMEOUT_S)

    def run(self, seconds: float) -> None:
        """``seconds`` of virtual time, every thread (the commander's too) running."""
        self.clock.run_for(seconds)

    def wait_for(self, predicate: Callable[[], object], timeout: float, what: str) -> Any:
        """Run until ``predicate()``, at most ``timeout`` s of virtual time; its value."""
        self.clock.run_until(predicate, timeout, what)
        return predicate()
