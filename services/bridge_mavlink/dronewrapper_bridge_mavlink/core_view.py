"""The MAVLink bridge's core as its sibling modules see it (:class:`BridgeCore`, a protocol that
:class:`dronewrapper_bridge_mavlink.core.BridgeCore` satisfies), and the :class:`Outbox` the
core fills for the node. Operations, missions, the receive side and the watches name the core
only through this view, so none of them imports the core that imports them. The parts the
core owns see less of it: its ``commands``, ``parameters`` and ``transfers`` each through a
protocol of its own, its ``missions`` (the envelope, home and mission state) nothing.
"""

from __future__ import annotations

import collections
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any, Protocol

from dronewrapper.msgs.mavros import ExtendedState, State
from dronewrapper.msgs.mavros import StatusText as StatusTextMsg
from dronewrapper.msgs.registry import Topic
from dronewrapper_bridge_base.core_view import PureCoreView
from dronewrapper_bridge_base.guided_failsafe import Failsafe
from dronewrapper_bridge_base.unattended import Unattended
from dronewrapper_bridge_mavlink.command_exchange import Commands
from dronewrapper_bridge_mavlink.config import Config
from dronewrapper_bridge_mavlink.freshness import Freshness
from dronewrapper_bridge_mavlink.mission_state import MissionState
from dronewrapper_bridge_mavlink.outgoing import Send
from dronewrapper_bridge_mavlink.parameters import Parameters
from dronewrapper_bridge_mavlink.sources import AutopilotSources
from dronewrapper_bridge_mavlink.streams import StreamRequests
from dronewrapper_bridge_mavlink.telemetry import StatusTextAssembler, Telemetry
from dronewrapper_bridge_mavlink.transfers import Transfers


@dataclass
class Outbox:
    """What the node must do after a core call.

    Attributes:
        sends: MAVLink messages for the autopilot, typed (the link encodes them).
        samples: (registry topic, message) to publish on Zenoh.
        peers: UDP addresses replies must go to from now on (the last one wins).
        errors: names of dropped inputs to count (the node's ``callback_errors``).
    """

    sends: list[Send] = field(default_factory=list)
    samples: list[tuple[Topic, Any]] = field(default_factory=list)
    peers: list[Any] = field(default_factory=list)
    errors: list[str] = field(default_factory=list)


class BridgeCore(PureCoreView, Protocol):
    """What the core's sibling modules read and call of it (times: ``now`` monotonic s,
    ``stamp`` wall-clock s for headers; positions local ENU m)."""

    @property
    def config(self) -> Config: ...
    @property
    def autopilot(self) -> str: ...  # "px4", "ardupilotmega" ("": not heard yet)
    @property
    def target_system(self) -> int: ...
    @property
    def connected(self) -> bool: ...
    @property
    def heartbeat_state(self) -> State | None: ...
    @property
    def ext(self) -> ExtendedState: ...
    @property
    def failsafe(self) -> Failsafe: ...
    @property
    def unattended(self) -> Unattended: ...
    @property
    def telemetry(self) -> Telemetry: ...
    @property
    def freshness(self) -> Freshness: ...
    @property
    def sources(self) -> AutopilotSources: ...
    @property
    def statustexts(self) -> StatusTextAssembler: ...
    @property
    def recent_texts(self) -> collections.deque[tuple[float, StatusTextMsg]]: ...
    @property
    def commands(self) -> Commands: ...
    @property
    def missions(self) -> MissionState: ...
    @property
    def parameters(self) -> Parameters: ...
    @property
    def transfers(self) -> Transfers: ...
    @property
    def streams(self) -> StreamRequests: ...

    def require_connected(self) -> str: ...
    def dropped(self, what: str) -> None: ...  # a dropped input, counted
    def on_mavlink(self, msg: Any, source: Any, now: float, stamp: float) -> None: ...
    def pose(self) -> tuple[tuple[float, float, float], float] | None: ...
    def streamed_for(self, now: float) -> float: ...  # s of setpoints streamed until now
    def mode_entered(self, mode: str) -> None: ...
    def bridge_text(self, text: str) -> None: ...
    def unattended_tick(self, holding: Callable[[], bool]) -> None: ...
    def publish_text(self, text: StatusTextMsg) -> None: ...
