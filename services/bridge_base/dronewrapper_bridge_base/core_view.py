"""What every bridge's sibling modules (operations, missions) read and call of the shared part
of its core, :class:`~dronewrapper_bridge_base.core_driver.PureCore`: a protocol each bridge's
own core view extends with its aircraft's parts, so that no sibling imports the core that
imports it.
"""

from __future__ import annotations

from typing import Any, Protocol

from dronewrapper.msgs.registry import Topic
from dronewrapper_bridge_base.operation import Operation, Steps


class PureCoreView(Protocol):
    """The :class:`~dronewrapper_bridge_base.core_driver.PureCore` side of a core (times:
    ``now`` monotonic s, ``stamp`` wall-clock s for headers)."""

    @property
    def now(self) -> float: ...
    @property
    def stamp(self) -> float: ...
    @property
    def caller(self) -> str: ...  # the commander of the request whose operation is starting
    @property
    def command_busy(self) -> bool: ...

    def publish(self, topic: Topic, msg: Any) -> None: ...
    def report_breach(self, limit: str, reason: str, action: str) -> None: ...
    def take_command_slot(self) -> None: ...
    def release_command_slot(self) -> None: ...
    def start(
        self, steps: Steps, now: float, stamp: float, *, background: bool = False
    ) -> Operation: ...
