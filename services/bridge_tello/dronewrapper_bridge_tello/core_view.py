"""The Tello core as its operations and missions see it (:class:`TelloCore`, a protocol that
:class:`dronewrapper_bridge_tello.core.TelloCore` satisfies), and the :class:`Outbox` the core
fills for the node. The sibling modules name the core only through this view, so none of them
imports the core that imports them.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Protocol

from dronewrapper.msgs.registry import Topic
from dronewrapper_bridge_base.operation import Operation, Steps
from dronewrapper_bridge_tello.config import Config
from dronewrapper_bridge_tello.failsafe import Failsafe
from dronewrapper_bridge_tello.mission_state import TelloMissions
from dronewrapper_bridge_tello.replies import ReplyMatcher
from dronewrapper_bridge_tello.telemetry import Telemetry


@dataclass
class Outbox:
    """What the node must do after a core call.

    Attributes:
        sends: SDK command strings for the Tello (``command``, ``rc 0 0 0 0`` ...), in order.
        samples: (registry topic, message) to publish on Zenoh.
        video_restart: a ``streamon`` is sent: the video receiver starts a new run (what
            arrives from now on is the new stream, decoded from its first key frame).
    """

    sends: list[str] = field(default_factory=list)
    samples: list[tuple[Topic, Any]] = field(default_factory=list)
    video_restart: bool = False


class TelloCore(Protocol):
    """What operations and missions read and call of the core (times: ``now`` monotonic s,
    ``stamp`` wall-clock s for headers)."""

    @property
    def now(self) -> float: ...
    @property
    def stamp(self) -> float: ...
    @property
    def caller(self) -> str: ...  # the commander of the request whose operation is starting
    @property
    def states_received(self) -> int: ...
    @property
    def command_busy(self) -> bool: ...
    @property
    def config(self) -> Config: ...
    @property
    def out(self) -> Outbox: ...
    @property
    def failsafe(self) -> Failsafe: ...
    @property
    def missions(self) -> TelloMissions: ...
    @property
    def telemetry(self) -> Telemetry: ...
    @property
    def matcher(self) -> ReplyMatcher: ...

    def send(self, text: str) -> None: ...
    def text(self, severity: int, text: str) -> None: ...
    def publish(self, topic: Topic, msg: Any) -> None: ...
    def publish_state(self, *, force: bool = False) -> None: ...
    def in_sdk_mode(self) -> None: ...
    def video_answered(self, command: str, reply: str | None) -> None: ...
    def require_connected(self) -> None: ...
    def take_command_slot(self) -> None: ...
    def release_command_slot(self) -> None: ...
    def report_breach(self, limit: str, reason: str, action: str) -> None: ...
    def start(
        self, steps: Steps, now: float, stamp: float, *, background: bool = False
    ) -> Operation: ...
