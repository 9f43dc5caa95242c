"""The pieces of a bridge's core that the ports of its sibling modules are made of: each
operation, mission side or receive handler states the port it uses as a protocol composed of
these and of the parts it reads (the core satisfies every one; no sibling imports the core
that imports it). What they name is the
:class:`~dronewrapper_bridge_base.core_driver.PureCore` side of a core.

Times: ``now`` monotonic s (set by each entry point of the core), ``stamp`` wall-clock s for
headers.
"""

from __future__ import annotations

from typing import Any, Protocol

from dronewrapper.msgs.registry import Topic
from dronewrapper_bridge_base.operation import Operation, Steps


class Clock(Protocol):
    """The core's time now (monotonic s)."""

    @property
    def now(self) -> float: ...


class Stamped(Clock, Protocol):
    """The core's time and the wall-clock stamp of what it publishes now (s)."""

    @property
    def stamp(self) -> float: ...


class CommandSlot(Protocol):
    """The one command exchange at a time the core's operations share."""

    @property
    def command_busy(self) -> bool: ...

    def take_command_slot(self) -> None: ...
    def release_command_slot(self) -> None: ...


class Publishing(Protocol):
    """A sample to publish on a registry topic."""

    def publish(self, topic: Topic, msg: Any) -> None: ...


class Starting(Protocol):
    """An operation to start (a background one: nobody waits for its reply)."""

    def start(
        self, steps: Steps, now: float, stamp: float, *, background: bool = False
    ) -> Operation: ...


class Serving(Stamped, Publishing, Starting, Protocol):
    """What a service operation of the mission side uses of the core besides its parts: the
    time, samples to publish, background operations, and the commander of the request whose
    operation is starting (``caller``)."""

    @property
    def caller(self) -> str: ...
