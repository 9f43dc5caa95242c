"""Missions, home and the safety envelope in bridge_mavlink (pure, over the core as
:class:`MissionPort` shows it).

:class:`MissionState` is what the core knows: the envelope in force, home (local ENU m and
geodetic), the mission the autopilot holds, the item being flown, and the one mission transfer
allowed at a time. The core checks each setpoint against its envelope
(:func:`dronewrapper_bridge_base.setpoint_envelope.refuse_setpoint`) and calls :func:`tick` (a
breach starts the envelope's action: hold, return or land; home, envelope and mission are
published).
:data:`HANDLERS` are the receive side of the mission protocol; the service operations
(:func:`push`, :func:`pull`, :func:`clear`, :func:`set_current`, :func:`control`,
:func:`set_envelope`) run the pure machines of :mod:`mission_transfer` through
:mod:`~dronewrapper_bridge_mavlink.uploads`, which also uploads the fence and, with a mission
that carries them, its rally points.

Frames: the envelope is ENU m in the home frame; a local position minus home (local ENU, from
HOME_POSITION; the local origin until it arrives) is in that frame. Mission items, rally
points and the fence uploaded to the autopilot are WGS-84 (home's geodetic position plus a
flat-earth offset: fine within the envelope's kilometre).
"""

from __future__ import annotations

import logging
import math
from collections.abc import Callable
from typing import Any, Protocol

from pymavlink.dialects.v20 import common as mavlink

from dronewrapper.msgs import registry
from dronewrapper.msgs.mavros import SetMode
from dronewrapper.msgs.mission import (
    EnvelopeSet,
    MissionResult,
    WaypointClear,
    WaypointPull,
    WaypointPullResult,
    WaypointPush,
    WaypointPushResult,
    WaypointReached,
    WaypointSetCurrent,
)
from dronewrapper.msgs.std import Header
from dronewrapper.runtime import ServiceError
from dronewrapper_bridge_base import envelope_set
from dronewrapper_bridge_base.core_view import Serving
from dronewrapper_bridge_base.envelope_state import BreachReporter, watch_breach
from dronewrapper_bridge_base.operation import Steps
from dronewrapper_bridge_mavlink import autopilot_limits, home_slot, mission_frames, uploads
from dronewrapper_bridge_mavlink import mission_transfer as mt
from dronewrapper_bridge_mavlink import operations as ops
from dronewrapper_bridge_mavlink.autopilot_limits import LimitsPort
from dronewrapper_bridge_mavlink.mission_state import MissionState
from dronewrapper_bridge_mavlink.modes import AUTOPILOT_PX4, HOLD_MODE
from dronewrapper_bridge_mavlink.uploads import UploadPort

log = logging.getLogger("bridge_mavlink")

SETTLE_WAIT_S = 1.0  # s a breach return waits for the autopilot's return altitude (once)


class MissionPort(LimitsPort, UploadPort, ops.OperationPort, Serving, BreachReporter, Protocol):
    """What the mission side uses of the core: the mission state it owns, what keeping the
    autopilot's limits (:class:`~.autopilot_limits.LimitsPort`), the uploads
    (:class:`~.uploads.UploadPort`), the operations it runs (a breach's hold or return, a
    mission item's set-current: :class:`~.operations.OperationPort`), a service operation
    (time, samples, the caller) and a breach's report use, and a dropped input's count."""

    missions: MissionState

    def dropped(self, what: str) -> None: ...


# ---------------------------------------------------------------- hooks the core calls


def tick(core: MissionPort) -> None:
    """Each stream tick: act on a breach, publish envelope, home and mission periodically."""
    state = core.missions
    action = watch_breach(core, state)
    if action:
        core.start(breach_action(core, action), core.now, core.stamp, background=True)
    if state.publish_due(core.now):
        publish_all(core)


def publish_all(core: MissionPort) -> None:
    state = core.missions
    core.publish(registry.ENVELOPE, state.envelope)
    publish_home(core)
    publish_waypoints(core)


def publish_home(core: MissionPort) -> None:
    core.publish(registry.HOME_POSITION, core.missions.home_message(core.stamp))


def publish_waypoints(core: MissionPort) -> None:
    core.publish(registry.MISSION_WAYPOINTS, core.missions.listing(core.stamp))


def breach_action(core: MissionPort, action: str) -> Steps:
    """The envelope's action after a breach: ``land`` or ``return`` (the failsafe's own
    requests; a return's altitude first kept under the ceiling, waiting up to
    :data:`SETTLE_WAIT_S` when it was not yet), or ``hold`` (the autopilot's hold mode)."""
    if action == "return" and not (yield from autopilot_limits.settled(core, SETTLE_WAIT_S)):
        core.bridge_text("breach return: the autopilot's return altitude is not confirmed")
    if action in ("land", "return"):
        return (yield from ops.failsafe_action(core, action))
    autopilot = core.autopilot or AUTOPILOT_PX4
    reply = yield from ops.set_mode(core, SetMode(custom_mode=HOLD_MODE[autopilot]))
    return reply.result


# ---------------------------------------------------------------- receive side


def on_home_position(core: MissionPort, msg: Any) -> None:
    """HOME_POSITION: home in both frames. One without a fix (latitude and longitude 0, as
    GLOBAL_POSITION_INT says "no fix") or with a non-finite local position is dropped and
    counted: a bad home must never move the fence, the returns or the go-tos."""
    local = (float(msg.y), float(msg.x), -float(msg.z))  # NED -> ENU
    if (msg.latitude == 0 and msg.longitude == 0) or not all(map(math.isfinite, local)):
        core.dropped("home_position")
        return
    core.telemetry.on_home_position(msg)
    geo = (msg.latitude / 1e7, msg.longitude / 1e7, msg.altitude / 1e3)
    moved, first = core.missions.on_home(local, geo)
    if moved:
        publish_home(core)
    if first:  # home known: the autopilot's return heights and fence
        follow_envelope(core)


def follow_envelope(core: MissionPort) -> None:
    """The envelope to the autopilot: return heights, fence action, fence (``upload_fence``)."""
    if core.config.upload_fence:
        core.start(uploads.push_fence(core, WaypointClear()), core.now, core.stamp, background=True)
    core.start(autopilot_limits.sync_steps(core), core.now, core.stamp, background=True)


def on_transfer_message(core: MissionPort, msg: Any) -> None:
    core.transfers.on_message(msg)
    if msg.get_type() == "MISSION_ACK":
        log.debug("MISSION_ACK %s", mt.result_name(msg.type))


def on_mission_current(core: MissionPort, msg: Any) -> None:
    if core.missions.on_current(home_slot.ours(int(msg.seq), core.autopilot) or 0):
        publish_waypoints(core)


def on_mission_item_reached(core: MissionPort, msg: Any) -> None:
    """MISSION_ITEM_REACHED, published once per item of this mission (:func:`home_slot.reached`;
    PX4 repeats it for a while)."""
    state = core.missions
    seq = home_slot.reached(int(msg.seq), core.autopilot, state.current_seq)
    if seq is not None and state.on_reached(seq):
        reached = WaypointReached(header=Header(stamp=core.stamp), wp_seq=seq)
        core.publish(registry.MISSION_REACHED, reached)


HANDLERS: dict[str, Callable[[MissionPort, Any], None]] = {
    "HOME_POSITION": on_home_position,
    "MISSION_REQUEST_INT": on_transfer_message,
    "MISSION_REQUEST": on_transfer_message,
    "MISSION_ACK": on_transfer_message,
    "MISSION_COUNT": on_transfer_message,
    "MISSION_ITEM_INT": on_transfer_message,
    "MISSION_CURRENT": on_mission_current,
    "MISSION_ITEM_REACHED": on_mission_item_reached,
}


# ---------------------------------------------------------------- operations


def push(core: MissionPort, request: WaypointPush) -> Steps:
    """mission/push: check every item and rally point against the envelope (and a return's
    climb to each rally point: :func:`autopilot_limits.check_rally_returns`; local items go
    up as global ones), upload the items, then any rally points (:func:`uploads.push_rally`)."""
    core.require_connected()
    state = core.missions
    try:
        waypoints = mission_frames.prepare(request.waypoints, state.envelope, state.home_geo)
        rally = None
        if request.rally is not None:
            rally = mission_frames.prepare(
                request.rally, state.envelope, state.home_geo, what="rally point"
            )
        if rally:
            yield from autopilot_limits.check_rally_returns(core, rally, state.envelope)
    except mission_frames.MissionFrameError as exc:
        raise ServiceError(str(exc), "refused") from None
    items = [uploads.item_of(wp) for wp in waypoints]
    offset = home_slot.offset(core.autopilot)
    held = home_slot.uploaded(items, core.autopilot, state.home_geo)  # as the autopilot holds them
    upload = yield from core.transfers.upload(held, numbered_from=offset)
    if not upload.error:
        state.new_mission(waypoints)
        publish_waypoints(core)
    transferred = max(0, upload.transferred - offset)
    error = upload.error
    message = error or f"{len(items)} item(s) uploaded"
    if not error and rally is not None:
        error = yield from uploads.push_rally(core.transfers, state, rally)
        message = error or f"{message} and {len(rally)} rally point(s)"
    return WaypointPushResult(success=not error, wp_transfered=transferred, message=message)


def pull(core: MissionPort, _request: WaypointPull) -> Steps:
    """mission/pull: download the autopilot's mission."""
    core.require_connected()
    download = yield from core.transfers.download()
    items = home_slot.downloaded(download.items, core.autopilot)
    waypoints = [uploads.waypoint_of(item) for item in items]
    if not download.error:
        core.missions.downloaded(waypoints)
        publish_waypoints(core)
    return WaypointPullResult(
        success=not download.error,
        wp_received=len(waypoints),
        message=download.error or f"{len(waypoints)} item(s) received",
        waypoints=waypoints,
    )


def clear(core: MissionPort, _request: WaypointClear) -> Steps:
    """mission/clear: MISSION_CLEAR_ALL."""
    core.require_connected()
    transfer = yield from core.transfers.clear()
    if not transfer.error:
        core.missions.cleared()
        publish_waypoints(core)
    return MissionResult(success=not transfer.error, message=transfer.error or "cleared")


def set_current(core: MissionPort, request: WaypointSetCurrent) -> Steps:
    """mission/set_current: MAV_CMD_DO_SET_MISSION_CURRENT."""
    core.require_connected()
    count = len(core.missions.waypoints)
    if count and request.wp_seq >= count:
        raise ValueError(f"wp_seq {request.wp_seq} is beyond the mission's {count} item(s)")
    result, message = yield from ops.command(
        core,
        mavlink.MAV_CMD_DO_SET_MISSION_CURRENT,
        float(home_slot.theirs(request.wp_seq, core.autopilot)),
    )
    return MissionResult(success=result == ops.ACCEPTED, message=message)


def set_envelope(core: MissionPort, request: EnvelopeSet) -> Steps:
    """envelope/set: replace or reset the envelope (neither: read it; see
    :mod:`dronewrapper_bridge_base.envelope_set`); refused when a return to a rally point
    uploaded before would climb too high under it (:func:`autopilot_limits.check_new_envelope`);
    the autopilot follows when connected and home is known (:func:`follow_envelope`)."""
    state = core.missions
    pose = core.pose()
    aircraft = None if pose is None else state.relative(*pose[0])[:2]
    yield from autopilot_limits.check_new_envelope(core, request)
    changed = envelope_set.apply(
        state, request, configured=core.config.envelope, caller=core.caller, aircraft=aircraft
    )
    if changed:
        core.publish(registry.ENVELOPE, state.envelope)
        log.info("envelope set by %r: %s", state.set_by or "the configuration", state.envelope)
        if core.connected and state.home_geo is not None:
            follow_envelope(core)
    yield from ()
    return envelope_set.result(state)


SERVICES: tuple[tuple[Any, Callable[..., Steps], str], ...] = (
    (registry.MISSION_PUSH, push, "mission"),
    (registry.MISSION_PULL, pull, ""),
    (registry.MISSION_CLEAR, clear, "mission"),
    (registry.MISSION_SET_CURRENT, set_current, "mission"),
    (registry.GEOFENCE_PUSH, uploads.push_fence, "mission"),
    (registry.ENVELOPE_SET, set_envelope, "envelope"),
)
"""(service, operation, the command-lease action that guards it; "" unguarded)."""
