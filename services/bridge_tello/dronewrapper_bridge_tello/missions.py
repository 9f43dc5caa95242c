"""The safety envelope and missions on the Tello (pure, over the core as :class:`MissionPort`
shows it; a setpoint's check over :class:`Refusing`).

Home is the take-off point (the Tello has no GPS; the bridge's position is dead-reckoned from
the take-off, x and y drifting by some decimetres a minute), so the envelope (ENU m in the home
frame, :mod:`dronewrapper.envelope`) is checked against that position.

* :func:`refuse_setpoint`, :func:`refuse_takeoff`: targets outside the envelope are refused
  with the limit named.
* :func:`tick`: a breach makes the Tello ``land`` (for ``land`` and ``return``: the Tello has
  no return-to-home) or ``stop`` (hover, for ``hold``).
* Missions are local: each :class:`~dronewrapper.msgs.mission.Waypoint` has frame
  MAV_FRAME_LOCAL_ENU (4) with ``x_lat``/``y_long``/``z_alt`` the point's east/north/up metres
  from home. They are flown as the Tello's own ``go x y z speed`` moves (forward, left, up cm
  in its heading frame, at most 5 m each: a longer leg is several moves), one after the other
  from the dead-reckoned position. What the Tello cannot do: global (GPS) waypoints, loiter
  times, a yaw per item, changing a move once sent (a pause takes effect after the current
  move), and ``return`` is a flight to home at the current height followed by ``land``.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Callable
from typing import Any, Protocol

from dronewrapper import envelope as env
from dronewrapper.envelope import Envelope, EnvelopeError
from dronewrapper.msgs import registry
from dronewrapper.msgs.mavros import LANDED_STATE_IN_AIR, PositionTarget
from dronewrapper.msgs.mission import (
    EnvelopeSet,
    HomePosition,
    MissionControl,
    MissionResult,
    WaypointClear,
    WaypointPush,
    WaypointPushResult,
    WaypointReached,
)
from dronewrapper.msgs.std import Header
from dronewrapper.runtime import ServiceError
from dronewrapper_bridge_base import envelope_set
from dronewrapper_bridge_base.core_view import Clock, Serving
from dronewrapper_bridge_base.operation import Steps
from dronewrapper_bridge_base.setpoint_limits import Kind
from dronewrapper_bridge_tello import operations as ops
from dronewrapper_bridge_tello.mission_state import TelloMissions

log = logging.getLogger("bridge_tello")


class Refusing(Clock, Protocol):
    """What a setpoint's check uses of the core besides its time: the mission state
    (envelope, the last refusal's text) and a text to publish."""

    missions: TelloMissions

    def text(self, severity: int, text: str) -> None: ...


class MissionPort(ops.OperationPort, Refusing, Serving, Protocol):
    """What the envelope's watch, the mission services and their flights use of the core
    besides the operations they run (:class:`~.operations.OperationPort`) and a service
    operation's (time, samples, background operations, the caller): a breach's report."""

    def report_breach(self, limit: str, reason: str, action: str) -> None: ...


FRAME_LOCAL_ENU = 4
MAX_MOVE_CM = 500
MIN_MOVE_CM = 20  # go refuses a move with all three axes within ±20 cm
REFUSAL_TEXT_PERIOD_S = 2.0
MOVE_SPEED_CM_S = 50  # go's speed, cm/s
MOVE_TIMEOUT_S = 15.0  # s for one move's "ok" (5 m at 50 cm/s and its settling)


def go_moves(east: float, north: float, up: float, yaw_enu: float) -> list[tuple[int, int, int]]:
    """The ``go`` moves (forward, left, up cm) that fly the ENU offset (m) from a Tello
    heading ``yaw_enu`` (rad): legs of at most 5 m per axis; none for an offset within 20 cm."""
    forward = east * math.cos(yaw_enu) + north * math.sin(yaw_enu)
    left = -east * math.sin(yaw_enu) + north * math.cos(yaw_enu)
    cm = [round(forward * 100), round(left * 100), round(up * 100)]
    if all(abs(v) <= MIN_MOVE_CM for v in cm):
        return []
    legs = max(1, math.ceil(max(abs(v) for v in cm) / MAX_MOVE_CM))
    moves = []
    done = [0, 0, 0]
    for leg in range(1, legs + 1):
        step = [round(v * leg / legs) - d for v, d in zip(cm, done, strict=True)]
        done = [d + s for d, s in zip(done, step, strict=True)]
        moves.append((step[0], step[1], step[2]))
    return moves


# ---------------------------------------------------------------- hooks the core calls


def refuse_setpoint(core: Refusing, target: PositionTarget, kind: Kind) -> EnvelopeError | None:
    """Why the envelope refuses ``target`` (the limit named), or None."""
    state = core.missions
    try:
        if kind is Kind.POSITION:
            p = target.required_position()
            env.check_position(state.envelope, p.x, p.y, p.z)
        else:
            v = target.velocity
            env.check_velocity(state.envelope, v.x, v.y, v.z)
            if kind is Kind.MIXED:
                env.check_position(state.envelope, 0.0, 0.0, target.required_position().z)
    except EnvelopeError as exc:
        reason = f"setpoint refused: {exc}"
        if core.now - state.last_refusal_text >= REFUSAL_TEXT_PERIOD_S:
            state.last_refusal_text = core.now
            log.warning("%s", reason)
            core.text(4, f"bridge: {reason}")
        return exc
    return None


def refuse_takeoff(envelope: Envelope, height: float) -> None:
    """A take-off to ``height`` m above ``envelope``'s ceiling: ServiceError naming it."""
    try:
        env.check_takeoff(envelope, height)
    except EnvelopeError as exc:
        raise ServiceError(str(exc), "refused") from None


def tick(core: MissionPort) -> None:
    """Each control tick: act on a breach; publish envelope, home and mission periodically."""
    state = core.missions
    position = core.telemetry.position_enu
    if position is not None and core.telemetry.landed.state == LANDED_STATE_IN_AIR:
        reason = state.monitor.update(state.envelope, position)
        if reason:
            action = state.envelope.breach_action
            done = "stop (hover)" if action == "hold" else "land"
            core.text(4, f"bridge: envelope breach: {reason}; {done}")
            log.warning("envelope breach: %s; %s", reason, done)
            core.report_breach(state.monitor.limit, reason, "hold" if action == "hold" else "land")
            state.paused = True
            core.start(breach_action(core, action), core.now, core.stamp, background=True)
    if state.publish_due(core.now):
        core.publish(registry.ENVELOPE, state.envelope)
        core.publish(registry.HOME_POSITION, HomePosition(header=Header(stamp=core.stamp)))
        publish_waypoints(core)


def breach_action(core: MissionPort, action: str) -> Steps:
    if action == "hold":
        reply = yield from ops.exchange(core, "stop")
        return reply
    return (yield from ops.failsafe_land(core))


def publish_waypoints(core: MissionPort) -> None:
    core.publish(registry.MISSION_WAYPOINTS, core.missions.listing(core.stamp))


# ---------------------------------------------------------------- services


def push(core: MissionPort, request: WaypointPush) -> Steps:
    """mission/push: local waypoints only, each inside the envelope; no rally points (the
    Tello's return flies home)."""
    if request.rally:
        raise ServiceError(
            f"the Tello has no rally points ({len(request.rally)} given): its return flies "
            "home. Upload the plan without its rallyPoints",
            "refused",
        )
    for seq, wp in enumerate(request.waypoints):
        if wp.frame != FRAME_LOCAL_ENU:
            raise ServiceError(
                f"mission item {seq}: the Tello has no GPS; give local waypoints "
                f"(frame {FRAME_LOCAL_ENU}, MAV_FRAME_LOCAL_ENU: east, north, up m from home)",
                "refused",
            )
        try:
            env.check_position(core.missions.envelope, wp.x_lat, wp.y_long, wp.z_alt)
        except EnvelopeError as exc:
            raise ServiceError(f"mission item {seq}: {exc}", "refused") from None
    state = core.missions
    if state.flying:
        raise ServiceError("a mission is being flown: pause it first", "refused")
    state.kept(request.waypoints)
    publish_waypoints(core)
    yield from ()
    count = len(state.waypoints)
    return WaypointPushResult(success=True, wp_transfered=count, message=f"{count} item(s) kept")


def clear(core: MissionPort, _request: WaypointClear) -> Steps:
    state = core.missions
    if state.flying:
        raise ServiceError("a mission is being flown: pause it first", "refused")
    state.kept([])
    publish_waypoints(core)
    yield from ()
    return MissionResult(success=True, message="cleared")


def control(core: MissionPort, request: MissionControl) -> Steps:
    """start (from the current item), pause (after the current move) or return (fly home at
    the current height, then land)."""
    core.require_connected()
    state = core.missions
    if core.telemetry.landed.state != LANDED_STATE_IN_AIR:
        raise ServiceError("the Tello is not flying: take off first", "refused")
    flying = state.flying
    if request.action == "pause":
        if not flying:
            raise ServiceError("pause refused: no mission is being flown", "refused")
        state.paused = True
        yield from ()
        return MissionResult(success=True, message="pausing after the current move")
    if flying and state.paused and request.action == "start":
        state.paused = False  # paused, its current move not yet done: it goes on
        yield from ()
        return MissionResult(success=True, message="resumed: the mission goes on")
    if flying:
        raise ServiceError("a mission or a return is being flown already", "refused")
    state.paused = False
    if request.action == "start":
        if not state.waypoints:
            raise ServiceError("no mission uploaded", "refused")
        steps = fly_mission(core)
    else:
        steps = fly_home(core)
    state.running = core.start(steps, core.now, core.stamp, background=True)
    yield from ()
    return MissionResult(success=True, message=f"{request.action}: flying")


def fly_to(core: MissionPort, target: tuple[float, float, float]) -> Steps:
    """Fly to ``target`` (ENU m from home) with go moves; False when paused or refused."""
    position = core.telemetry.position_enu or (0.0, 0.0, 0.0)
    east, north, up = (t - p for t, p in zip(target, position, strict=True))
    for move in go_moves(east, north, up, core.telemetry.yaw_enu):
        if core.missions.paused:
            return False
        command = f"go {move[0]} {move[1]} {move[2]} {MOVE_SPEED_CM_S}"
        reply = yield from ops.exchange(core, command, timeout=MOVE_TIMEOUT_S, attempts=1)
        if reply is None or not ops.is_ok(reply):
            core.text(4, f"bridge: mission: {command} -> {reply or 'no reply'}")
            return False
    return True


def fly_mission(core: MissionPort) -> Steps:
    state = core.missions
    while state.current_seq < len(state.waypoints) and not state.paused:
        wp = state.waypoints[state.current_seq]
        arrived = yield from fly_to(core, (wp.x_lat, wp.y_long, wp.z_alt))
        if not arrived:
            return False
        core.publish(
            registry.MISSION_REACHED,
            WaypointReached(header=Header(stamp=core.stamp), wp_seq=state.current_seq),
        )
        state.current_seq += 1
        publish_waypoints(core)
    return True


def fly_home(core: MissionPort) -> Steps:
    z = (core.telemetry.position_enu or (0.0, 0.0, 1.0))[2]
    arrived = yield from fly_to(core, (0.0, 0.0, z))
    if arrived:
        yield from ops.landing(core)
    return arrived


def set_envelope(core: MissionPort, request: EnvelopeSet) -> Steps:
    """envelope/set: replace or reset the envelope, or read it
    (:mod:`dronewrapper_bridge_base.envelope_set`; home is the take-off point)."""
    state = core.missions
    position = core.telemetry.position_enu
    aircraft = None if position is None else (position[0], position[1])
    changed = envelope_set.apply(
        state, request, configured=core.config.envelope, caller=core.caller, aircraft=aircraft
    )
    if changed:
        core.publish(registry.ENVELOPE, state.envelope)
        log.info("envelope set by %r: %s", state.set_by or "the configuration", state.envelope)
    yield from ()
    return envelope_set.result(state)


SERVICES: tuple[tuple[Any, Callable[..., Steps], str], ...] = (
    (registry.MISSION_PUSH, push, "mission"),
    (registry.MISSION_CLEAR, clear, "mission"),
    (registry.MISSION_CONTROL, control, "mission"),
    (registry.ENVELOPE_SET, set_envelope, "envelope"),
)
"""(service, operation, the command-lease action that guards it)."""
