"""Go-to, return and a mission's start, pause and resume: each one waiting operation (pure).

Like take-off and landing (:mod:`~dronewrapper_bridge_mavlink.flight`), each answers with a
:class:`~dronewrapper.msgs.flight.FlightResult` at its end, so a client never names an
autopilot's modes nor reads its status texts:

- go-to: refused at once on the ground (take off first), outside the envelope (the limit
  named) or when home stays unknown for :data:`HOME_WAIT_S` (``no_home``: the point cannot
  be placed, never a guess); else the autopilot's guided mode (PX4 OFFBOARD, primed;
  ArduPilot GUIDED) and the bridge's own position hold at the point
  (:meth:`~dronewrapper_bridge_base.guided_failsafe.Failsafe.hold_at`), done within ``tolerance``.
  A timeout holds where the aircraft is.
- return: refused on the ground; the autopilot's return (its altitude kept under the
  envelope's ceiling, :mod:`~dronewrapper_bridge_mavlink.autopilot_limits`), done once on the
  ground and disarmed.
- mission: start or resume refused with no mission or on the ground; pause refused when no
  mission is being flown; else the autopilot's mission or hold mode.

A go-to, return or mission started with a ``watch`` key is watched (the core's
:class:`~dronewrapper_bridge_base.unattended.Unattended`): if that commander's process stops
beating, the bridge ends the action as for a lost commander. Positions ENU m from home
(the home frame, see :mod:`~dronewrapper_bridge_mavlink.missions`), time the core's. The core
is seen as :class:`ActionPort` shows it.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Generator
from typing import Protocol

from pymavlink.dialects.v20 import common as mavlink

from dronewrapper.msgs import flight
from dronewrapper.msgs.mavros import SetMode
from dronewrapper.msgs.mission import MissionControl, MissionResult
from dronewrapper.runtime import ServiceError
from dronewrapper_bridge_base.flight_request import goto_target
from dronewrapper_bridge_base.guided_flight import flying, returned
from dronewrapper_bridge_base.operation import Steps
from dronewrapper_bridge_base.unattended import Unattended
from dronewrapper_bridge_mavlink import autopilot_limits
from dronewrapper_bridge_mavlink import operations as ops
from dronewrapper_bridge_mavlink.flight import (
    MAX_TIMEOUT_S,
    FlightPort,
    checked,
    failed,
    last_text,
)
from dronewrapper_bridge_mavlink.modes import (
    AUTOPILOT_PX4,
    GUIDED_MODE,
    HOLD_MODE,
    LAND_MODE,
    RETURN_MODE,
)
from dronewrapper_bridge_mavlink.setpoints import hold_target

log = logging.getLogger("bridge_mavlink")

HOME_WAIT_S = 5.0
"""How long a go-to waits for home to be known (s): HOME_POSITION comes at 0.5-1 Hz."""
MISSION_MODE = {AUTOPILOT_PX4: "AUTO.MISSION", "ardupilotmega": "AUTO"}
SETTLE_WAIT_S = 2.0  # s a return waits for the autopilot's return altitude to be kept
MISSION_CHECK_WAIT_S = 5.0  # s a start may wait for the autopilot to accept a new mission


class ActionPort(autopilot_limits.LimitsPort, FlightPort, Protocol):
    """What go-to, return and mission actions use of the core besides what take-off and
    landing do (:class:`~.flight.FlightPort`) and keeping the autopilot's limits
    (:class:`~.autopilot_limits.LimitsPort`): the unattended rule."""

    unattended: Unattended


def not_flying(what: str) -> flight.FlightResult:
    return failed(flight.REFUSED, f"{what} refused: not flying (take off first)", what)


def wait_for_home(core: ActionPort) -> Generator[float, None, bool]:
    """Wait up to :data:`HOME_WAIT_S` for home; whether it is known."""
    deadline = core.now + HOME_WAIT_S
    while not core.missions.home_known:
        if core.now >= deadline:
            return False
        yield deadline
    return True


def goto_point(core: ActionPort, request: flight.GotoRequest) -> Steps:
    """Fly to the point and hold there (see module docstring)."""
    timeout = checked("timeout", request.timeout, 0.0, MAX_TIMEOUT_S)
    tolerance = checked("tolerance", request.tolerance, 0.0, 100.0)
    if not core.connected:
        return failed(flight.NOT_READY, "the autopilot is not connected (no heartbeat)")
    if not flying(core):
        return not_flying("goto")
    if not (yield from wait_for_home(core)):
        return failed(
            flight.NO_HOME, f"home is not known after {HOME_WAIT_S:g} s: no point to fly to"
        )
    target = goto_target(core.missions, request)
    if isinstance(target, flight.FlightResult):
        return target
    autopilot = core.autopilot or AUTOPILOT_PX4
    mode = GUIDED_MODE[autopilot]
    if ops.shown_mode(core) != mode:
        reply = yield from ops.set_mode(core, SetMode(custom_mode=mode))
        if not reply.mode_sent:
            return failed(flight.REFUSED, reply.message, f"set_mode {mode}", reply.result)
    core.failsafe.hold_at(hold_target(target, core.telemetry.yaw_enu))
    start_watch(core, "goto", request.watch)
    try:
        return (yield from fly_to(core, target, mode, tolerance, timeout))
    finally:
        core.unattended.ended(core.now)  # reached, given up or cancelled: the go-to is over


def fly_to(
    core: ActionPort,
    target: tuple[float, float, float],
    mode: str,
    tolerance: float,
    timeout: float,
) -> Steps:
    """Wait until within ``tolerance`` m of ``target`` (local ENU m), the bridge holding it."""
    deadline = core.now + timeout
    while True:
        position = core.telemetry.position_enu
        distance = math.dist(position, target) if position is not None else math.inf
        if distance <= tolerance:
            return flight.FlightResult(success=True, message=f"at the point: {distance:.2f} m away")
        hb = core.heartbeat_state
        if hb is not None and not hb.armed:
            return failed(flight.REFUSED, f"the autopilot disarmed{last_text(core)}", "goto")
        if hb is not None and hb.mode != mode:
            text = f"the autopilot left {mode} for {hb.mode}{last_text(core)}"
            return failed(flight.REFUSED, text, "goto")
        if core.now >= deadline:
            core.hold_here()  # the go-to ends here: no flying on toward the point
            return failed(
                flight.TOO_LATE,
                f"not within {tolerance:g} m after {timeout:g} s: {distance:.1f} m away",
            )
        yield deadline


def start_return(core: ActionPort) -> Generator[float, None, tuple[int, str]]:
    """Ask for the autopilot's return, its altitude first kept under the ceiling:
    (MAV_RESULT, explanation)."""
    kept = yield from autopilot_limits.settled(core, SETTLE_WAIT_S)
    problem = core.missions.limits.problem if kept else "not confirmed in time"
    autopilot = core.autopilot or AUTOPILOT_PX4
    mode = RETURN_MODE[autopilot]
    core.failsafe.release_hold()
    core.failsafe.on_mode_requested(mode, core.now)
    core.failsafe.on_mode_requested(LAND_MODE[autopilot], core.now)
    result, message = yield from ops.command(core, mavlink.MAV_CMD_NAV_RETURN_TO_LAUNCH)
    if result == ops.ACCEPTED:
        core.mode_entered(mode)
    if problem:
        message += f" (the autopilot's own return altitude: {problem})"
    return result, message


def return_home(core: ActionPort, request: flight.ReturnRequest) -> Steps:
    """The autopilot's return, its altitude under the ceiling; done on the ground, disarmed."""
    timeout = checked("timeout", request.timeout, 0.0, MAX_TIMEOUT_S)
    if not core.connected:
        return failed(flight.NOT_READY, "the autopilot is not connected (no heartbeat)")
    if not flying(core):
        return not_flying("return")
    autopilot = core.autopilot or AUTOPILOT_PX4
    mode = RETURN_MODE[autopilot]
    result, message = yield from start_return(core)
    if result != ops.ACCEPTED:
        return failed(flight.REFUSED, message, "return", result)
    start_watch(core, "return", request.watch)
    deadline = core.now + timeout
    modes = (mode, LAND_MODE[autopilot])
    return (yield from returned(core, modes, deadline, timeout, "the autopilot"))


def mission_action(core: ActionPort, request: flight.MissionRequest) -> Steps:
    """Start, pause or resume the uploaded mission (see module docstring)."""
    timeout = checked("timeout", request.timeout, 0.0, MAX_TIMEOUT_S)
    if not core.connected:
        return failed(flight.NOT_READY, "the autopilot is not connected (no heartbeat)")
    refusal = mission_refusal(core, request.action)
    if refusal:
        return failed(flight.REFUSED, refusal, request.action)
    autopilot = core.autopilot or AUTOPILOT_PX4
    if request.action == "pause":
        reply = yield from ops.set_mode(core, SetMode(custom_mode=HOLD_MODE[autopilot]))
        if not reply.mode_sent:
            return failed(flight.REFUSED, reply.message, "pause", reply.result)
        return flight.FlightResult(success=True, message="mission paused: holding here")
    mode = MISSION_MODE[autopilot]
    if request.action == "start":
        core.missions.started()
        if autopilot != AUTOPILOT_PX4 and ops.shown_mode(core) == mode:
            # ArduPilot starts a mission (again, once finished) only on entering AUTO
            reply = yield from ops.set_mode(core, SetMode(custom_mode=GUIDED_MODE[autopilot]))
            if not reply.mode_sent:
                return failed(flight.REFUSED, reply.message, request.action, reply.result)
    deadline = core.now + min(timeout, MISSION_CHECK_WAIT_S)
    core.failsafe.release_hold()
    while True:
        reply = yield from ops.set_mode(core, SetMode(custom_mode=mode))
        busy = reply.result == mavlink.MAV_RESULT_TEMPORARILY_REJECTED
        if reply.mode_sent:
            break
        if not busy or core.now >= deadline:
            return failed(flight.REFUSED, reply.message, request.action, reply.result)
        retry = core.now + 0.5  # PX4 refuses the mission mode until it has checked the upload
        while core.now < retry:
            yield retry
    start_watch(core, "mission", request.watch)
    seq, total = core.missions.current_seq, len(core.missions.waypoints)
    return flight.FlightResult(
        success=True, message=f"flying the mission from item {seq} of {total}"
    )


def start_watch(core: ActionPort, what: str, key: str) -> None:
    """The ``what`` started now is watched for its commander's process (``key``)."""
    core.unattended.start(what, key, core.now)
    log.info("%s: its commander's process %s", what, f"is {key}" if key else "is not known")


def mission_refusal(core: ActionPort, action: str) -> str:
    """Why a mission ``action`` (start, resume, pause, return) cannot be done now, or ""."""
    autopilot = core.autopilot or AUTOPILOT_PX4
    if action in ("start", "resume") and not core.missions.waypoints:
        return f"{action} refused: no mission uploaded"
    if action in ("start", "resume", "return") and not flying(core):
        return f"{action} refused: not flying (take off first)"
    if action == "pause" and ops.shown_mode(core) != MISSION_MODE[autopilot]:
        return f"pause refused: no mission is being flown (mode {ops.shown_mode(core) or '?'})"
    return ""


def control(core: ActionPort, request: MissionControl) -> Steps:
    """mission/control (a ground station's buttons): ``start``, ``pause`` or ``return``,
    answered once the autopilot has taken it (a return does not wait for the landing); the
    same refusals as :func:`mission_action` and :func:`return_home`."""
    core.require_connected()
    refusal = mission_refusal(core, request.action)
    if refusal:
        raise ServiceError(refusal, "refused")
    if request.action == "return":
        result, message = yield from start_return(core)
        return MissionResult(success=result == ops.ACCEPTED, message=message)
    reply = yield from mission_action(core, flight.MissionRequest(action=request.action))
    return MissionResult(success=reply.success, message=reply.message)
