"""The bridge's receive side: one function per MAVLink message kind, over the pure core.

:func:`admit` decides whether a message may be used at all (a second autopilot with the same
system id, a duplicated or reordered datagram, a non-finite pose are dropped); the handlers in
:data:`HANDLERS` update the core's knowledge and queue the samples to publish. Time is the
core's ``now`` (monotonic s) and ``stamp`` (wall-clock s for headers).
"""

from __future__ import annotations

import logging
import math
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

from dronewrapper.msgs import registry
from dronewrapper_bridge_mavlink import commands as cmds
from dronewrapper_bridge_mavlink import missions
from dronewrapper_bridge_mavlink.freshness import boot_ms_of
from dronewrapper_bridge_mavlink.link_gap import gap_report
from dronewrapper_bridge_mavlink.telemetry import (
    battery_from_battery_status,
    battery_from_sys_status,
    extended_state,
    is_autopilot_heartbeat,
    non_finite_field,
    state_from_heartbeat,
)

if TYPE_CHECKING:
    from dronewrapper_bridge_mavlink.core import BridgeCore

log = logging.getLogger("bridge_mavlink")


def admit(core: BridgeCore, msg: Any, kind: str, source: Any) -> bool:
    """False for a message to drop: from a second autopilot with the same system id, a
    duplicated datagram, or one older than what was already used (seq / time_boot_ms)."""
    system = msg.get_srcSystem()
    verdict = core.sources.check(source, system, core.now)
    if verdict.flag:
        core.bridge_text(verdict.flag)
    if not verdict.accept:
        return False
    if source is not None and system == core.target_system:
        core.out.peers.append(core.sources.owner(system))
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
        return False
    bad_field = non_finite_field(kind, msg)
    if bad_field is not None:
        core.out.errors.append("mavlink non-finite")
        log.debug("dropped %s", bad_field)
        return False
    return True


def on_heartbeat(core: BridgeCore, msg: Any) -> None:
    if not is_autopilot_heartbeat(msg):
        return
    if core.target_system and msg.get_srcSystem() != core.target_system:
        return
    if not core.target_system:
        core.target_system = msg.get_srcSystem()
        core.target_component = msg.get_srcComponent()
    before, lost_for = core.heartbeat_state, core.now - core.last_heartbeat
    core.last_heartbeat = core.now
    state = state_from_heartbeat(msg, core.stamp, failsafe=core.failsafe.state)
    if state.autopilot != core.autopilot:
        core.autopilot = state.autopilot
        log.info(
            "autopilot %s (system %d, component %d)",
            core.autopilot,
            core.target_system,
            core.target_component,
        )
    reconnected = not core.connected
    core.connected = True
    core.heartbeat_state = state
    core.update_failsafe_vehicle()
    if reconnected:
        log.info("connected to the autopilot (mode %s)", state.mode)
        core.rates_round = 0
        core.next_rates = core.now
        if before is not None:  # after a link gap: what the autopilot changed meanwhile
            report = gap_report(before, state, lost_for)
            if report is not None:
                core.bridge_text(report)
    core.publish_state()


def on_attitude(core: BridgeCore, msg: Any) -> None:
    core.telemetry.on_attitude(msg)


def on_attitude_quaternion(core: BridgeCore, msg: Any) -> None:
    core.telemetry.on_attitude_quaternion(msg)


def on_local_position_ned(core: BridgeCore, msg: Any) -> None:
    pose, local, body = core.telemetry.on_local_position(msg, core.stamp)
    core.publish(registry.LOCAL_POSE, pose)
    core.publish(registry.VELOCITY_LOCAL, local)
    core.publish(registry.VELOCITY_BODY, body)


def on_global_position_int(core: BridgeCore, msg: Any) -> None:
    fix = core.telemetry.on_global_position(msg, core.stamp)
    max_hz = core.config.global_position_max_hz
    if fix is not None and (max_hz <= 0 or core.now - core.last_global_pub >= 0.9 / max_hz):
        core.last_global_pub = core.now
        core.publish(registry.GLOBAL_POSITION, fix)


def on_gps_raw_int(core: BridgeCore, msg: Any) -> None:
    core.telemetry.on_gps_raw(msg)


def on_home_position(core: BridgeCore, msg: Any) -> None:
    core.telemetry.on_home_position(msg)


def on_extended_sys_state(core: BridgeCore, msg: Any) -> None:
    ext = extended_state(msg, core.stamp)
    changed = (ext.landed_state, ext.vtol_state) != (
        core.ext.landed_state,
        core.ext.vtol_state,
    )
    core.ext = ext
    if changed:
        core.update_failsafe_vehicle()
        core.last_ext_pub = core.now
        core.publish(registry.EXTENDED_STATE, ext)


def on_sys_status(core: BridgeCore, msg: Any) -> None:
    battery = battery_from_sys_status(msg, core.stamp)
    known = core.battery is not None and not math.isnan(core.battery.percentage)
    if not known or not math.isnan(battery.percentage):
        core.battery = battery


def on_battery_status(core: BridgeCore, msg: Any) -> None:
    if msg.id == 0:
        core.battery = battery_from_battery_status(msg, core.stamp)


def on_statustext(core: BridgeCore, msg: Any) -> None:
    for text in core.statustexts.add(msg, core.stamp, core.now):
        core.publish_text(text)


def on_command_ack(core: BridgeCore, msg: Any) -> None:
    target = (getattr(msg, "target_system", 0), getattr(msg, "target_component", 0))
    ours = (core.config.source_system, core.config.source_component)
    if target != (0, 0) and target != ours:
        return  # the answer to a ground station's command (forwarded), not to ours
    outcome = core.acks.on_ack(int(msg.command), int(msg.result), core.now)
    log.debug(
        "COMMAND_ACK %s %s (%s)",
        cmds.command_name(msg.command),
        cmds.result_name(msg.result),
        outcome,
    )


def on_param_value(core: BridgeCore, msg: Any) -> None:
    param_id = msg.param_id
    if isinstance(param_id, bytes | bytearray):
        param_id = bytes(param_id).decode("ascii", "replace")
    param_id = param_id.split("\x00", 1)[0]
    core.param_values_received += 1
    core.params[param_id] = (
        float(msg.param_value),
        int(msg.param_type),
        core.param_values_received,
    )


HANDLERS: dict[str, Callable[[BridgeCore, Any], None]] = {
    "ATTITUDE": on_attitude,
    "ATTITUDE_QUATERNION": on_attitude_quaternion,
    "LOCAL_POSITION_NED": on_local_position_ned,
    "GLOBAL_POSITION_INT": on_global_position_int,
    "GPS_RAW_INT": on_gps_raw_int,
    "HOME_POSITION": on_home_position,
    "EXTENDED_SYS_STATE": on_extended_sys_state,
    "SYS_STATUS": on_sys_status,
    "BATTERY_STATUS": on_battery_status,
    "STATUSTEXT": on_statustext,
    "COMMAND_ACK": on_command_ack,
    "PARAM_VALUE": on_param_value,
}
HANDLERS.update(missions.HANDLERS)  # the mission protocol, home (missions.py)
