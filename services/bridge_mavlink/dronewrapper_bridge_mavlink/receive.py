"""The bridge's receive side: which messages may be used, and the telemetry handlers.

:func:`admission` decides whether a message may be used at all (a second autopilot with the
same system id, a duplicated or reordered datagram, a non-finite pose are dropped) and returns
what the core must do about it. The handlers in :data:`HANDLERS` feed the objects that own the
telemetry (the core's ``telemetry``, ``statustexts``, ``commands``, ``parameters``) and queue the
samples to publish; what changes the core's own state (heartbeat, landed state, battery) is the
core's. Time is the core's ``now`` (monotonic s) and ``stamp`` (wall-clock s for headers).
"""

from __future__ import annotations

import logging
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from dronewrapper.msgs import registry
from dronewrapper_bridge_mavlink import commands as cmds
from dronewrapper_bridge_mavlink import missions
from dronewrapper_bridge_mavlink.freshness import boot_ms_of
from dronewrapper_bridge_mavlink.telemetry import non_finite_field

if TYPE_CHECKING:
    from dronewrapper_bridge_mavlink.core_view import BridgeCore

log = logging.getLogger("bridge_mavlink")


@dataclass(frozen=True)
class Admission:
    """Whether a received message may be used, and what the core must do about it: report
    ``flag`` (a second autopilot ...), reply to ``peer`` from now on, count ``error``."""

    accept: bool
    flag: str = ""
    peer: Any = None
    error: str = ""


def admission(core: BridgeCore, msg: Any, kind: str, source: Any) -> Admission:
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


def on_attitude(core: BridgeCore, msg: Any) -> None:
    core.telemetry.on_attitude(msg)


def on_attitude_quaternion(core: BridgeCore, msg: Any) -> None:
    core.telemetry.on_attitude_quaternion(msg)
    core.streams.on_quaternion(core.now)


def on_local_position_ned(core: BridgeCore, msg: Any) -> None:
    pose, local, body = core.telemetry.on_local_position(msg, core.stamp)
    core.publish(registry.LOCAL_POSE, pose)
    core.publish(registry.VELOCITY_LOCAL, local)
    core.publish(registry.VELOCITY_BODY, body)


def on_gps_raw_int(core: BridgeCore, msg: Any) -> None:
    core.telemetry.on_gps_raw(msg)


def on_statustext(core: BridgeCore, msg: Any) -> None:
    for text in core.statustexts.add(msg, core.stamp, core.now):
        core.publish_text(text)


def on_command_ack(core: BridgeCore, msg: Any) -> None:
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


def on_param_value(core: BridgeCore, msg: Any) -> None:
    core.parameters.on_value(msg)


def on_batch(core: BridgeCore, batch: Sequence[Any], now: float, stamp: float) -> None:
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


HANDLERS: dict[str, Callable[[BridgeCore, Any], None]] = {
    "ATTITUDE": on_attitude,
    "ATTITUDE_QUATERNION": on_attitude_quaternion,
    "LOCAL_POSITION_NED": on_local_position_ned,
    "GPS_RAW_INT": on_gps_raw_int,
    "STATUSTEXT": on_statustext,
    "COMMAND_ACK": on_command_ack,
    "PARAM_VALUE": on_param_value,
}
HANDLERS.update(missions.HANDLERS)  # the mission protocol, home (missions.py)
