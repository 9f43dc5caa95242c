"""The bridge's receive side: which messages may be used, and the telemetry handlers.

:func:`admission` decides whether a message may be used at all (a second autopilot with the
same system id, a duplicated or reordered datagram, a non-finite pose are dropped) and returns
what the core must do about it. The handlers in :data:`HANDLERS` feed the objects that own the
telemetry (the core's ``telemetry``, ``statustexts``, ``commands``, ``parameters``) and queue the
samples to publish; what changes the core's own state (heartbeat, landed state, battery) is the
core's, and the mission protocol's messages are the mission side's (``missions.HANDLERS``; the
core dispatches to both). Each function sees the core only through the small protocol it
needs (:class:`AdmissionPort`, :class:`ReceivePort`, :class:`BatchPort`). Time is the core's
``now`` (monotonic s) and ``stamp`` (wall-clock s for headers).
"""

from __future__ import annotations

import logging
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any, Protocol

from dronewrapper.msgs import registry
from dronewrapper.msgs.mavros import StatusText as StatusTextMsg
from dronewrapper_bridge_base.core_view import Clock, Publishing, Stamped
from dronewrapper_bridge_mavlink import commands as cmds
from dronewrapper_bridge_mavlink.command_exchange import Commands
from dronewrapper_bridge_mavlink.config import Config
from dronewrapper_bridge_mavlink.freshness import Freshness, boot_ms_of
from dronewrapper_bridge_mavlink.parameters import HasParameters
from dronewrapper_bridge_mavlink.sources import AutopilotSources
from dronewrapper_bridge_mavlink.streams import StreamRequests
from dronewrapper_bridge_mavlink.telemetry import StatusTextAssembler, Telemetry, non_finite_field

log = logging.getLogger("bridge_mavlink")


class AdmissionPort(Clock, Protocol):
    """What :func:`admission` reads of the core besides its time: the autopilot's system id
    (0 before it is heard), the senders seen and the freshness of each sender's messages."""

    target_system: int
    sources: AutopilotSources
    freshness: Freshness


class ReceivePort(Stamped, Publishing, HasParameters, Protocol):
    """What the telemetry handlers use of the core besides its time, its samples and its
    parameters: the config (our own address), the parts fed (telemetry, stream requests,
    status texts, commands) and a status text to publish."""

    config: Config
    telemetry: Telemetry
    streams: StreamRequests
    statustexts: StatusTextAssembler
    commands: Commands

    def publish_text(self, text: StatusTextMsg) -> None: ...


class BatchPort(Protocol):
    """What :func:`on_batch` calls of the core: one message's handling, a dropped one's count."""

    def on_mavlink(self, msg: Any, source: Any, now: float, stamp: float) -> None: ...
    def dropped(self, what: str) -> None: ...


@dataclass(frozen=True)
class Admission:
    """Whether a received message may be used, and what the core must do about it: report
    ``flag`` (a second autopilot ...), reply to ``peer`` from now on, count ``error``."""

    accept: bool
    flag: str = ""
    peer: Any = None
    error: str = ""


def admission(core: AdmissionPort, msg: Any, kind: str, source: Any) -> Admission:
    """Drop a message from a second autopilot with the same system id, a duplicated datagram,
    one older than what was already used (seq / time_boot_ms), or one with a non-finite
    field."""
    system = msg.get_srcSystem()
    verdict = core.sources.check(source, system, core.now)
    if not verdict.accept:
        return Admission(False, verdict.flag)
    peer = None
    if source is not None and system == core.target_system:
        peer = core.sources.owner(system)
    fresh = core.freshness.check(
        source,
        system,
        msg.get_srcComponent(),
        msg.get_seq(),
        kind,
        boot_ms_of(msg),
        core.now,
        bytes(msg.get_msgbuf() or b""),
    )
    if not fresh.new:
        log.debug("dropped %s: %s", kind, fresh.reason)
        return Admission(False, verdict.flag, peer)
    bad_field = non_finite_field(kind, msg)
    if bad_field is not None:
        log.debug("dropped %s", bad_field)
        return Admission(False, verdict.flag, peer, "mavlink non-finite")
    return Admission(True, verdict.flag, peer)


def on_attitude(core: ReceivePort, msg: Any) -> None:
    core.telemetry.on_attitude(msg)


def on_attitude_quaternion(core: ReceivePort, msg: Any) -> None:
    core.telemetry.on_attitude_quaternion(msg)
    core.streams.on_quaternion(core.now)


def on_local_position_ned(core: ReceivePort, msg: Any) -> None:
    pose, local, body = core.telemetry.on_local_position(msg, core.stamp)
    core.publish(registry.LOCAL_POSE, pose)
    core.publish(registry.VELOCITY_LOCAL, local)
    core.publish(registry.VELOCITY_BODY, body)


def on_gps_raw_int(core: ReceivePort, msg: Any) -> None:
    core.telemetry.on_gps_raw(msg)


def on_statustext(core: ReceivePort, msg: Any) -> None:
    for text in core.statustexts.add(msg, core.stamp, core.now):
        core.publish_text(text)


def on_command_ack(core: ReceivePort, msg: Any) -> None:
    target = (getattr(msg, "target_system", 0), getattr(msg, "target_component", 0))
    ours = (core.config.source_system, core.config.source_component)
    if target != (0, 0) and target != ours:
        return  # the answer to a ground station's command (forwarded), not to ours
    outcome = core.commands.on_ack(int(msg.command), int(msg.result))
    log.debug(
        "COMMAND_ACK %s %s (%s)",
        cmds.command_name(msg.command),
        cmds.result_name(msg.result),
        outcome,
    )


def on_param_value(core: ReceivePort, msg: Any) -> None:
    core.parameters.on_value(msg)


def on_batch(core: BatchPort, batch: Sequence[Any], now: float, stamp: float) -> None:
    """Every message one wake-up of the receive thread read (each with ``msg`` and its
    ``source``), in order, at one time (they arrived together): one call of the core for all
    of them. A message whose handling raises is logged and counted (``mavlink``); the others
    are handled."""
    for received in batch:
        try:
            core.on_mavlink(received.msg, received.source, now, stamp)
        except Exception:
            core.dropped("mavlink")
            log.exception("error handling %s", type(received.msg).__name__)


HANDLERS: dict[str, Callable[[ReceivePort, Any], None]] = {
    "ATTITUDE": on_attitude,
    "ATTITUDE_QUATERNION": on_attitude_quaternion,
    "LOCAL_POSITION_NED": on_local_position_ned,
    "GPS_RAW_INT": on_gps_raw_int,
    "STATUSTEXT": on_statustext,
    "COMMAND_ACK": on_command_ack,
    "PARAM_VALUE": on_param_value,
}
