"""Go-to, return and a mission's start, pause and resume on the Tello: one waiting operation
each (pure), answered with a :class:`~dronewrapper.msgs.flight.FlightResult` like take-off.

The Tello has no GPS: home is the take-off point, so a go-to is local only (a latitude and
longitude is ``no_home``) and is flown as ``go`` moves
(:func:`~dronewrapper_bridge_tello.missions.fly_to`); a return flies home at the current
height and lands (:func:`~dronewrapper_bridge_tello.missions.fly_home`); a mission's start and
resume start its moves in the background, a pause takes effect after the current move. All
are refused on the ground; while the bridge flies them no commander steers, so none is lost
(the setpoint watchdog forgets the last setpoint). Positions ENU m from home, time the core's.
"""

from __future__ import annotations

import math
from typing import Protocol

from dronewrapper import envelope as env
from dronewrapper.envelope import EnvelopeError
from dronewrapper.msgs import flight
from dronewrapper.msgs.mavros import LANDED_STATE_IN_AIR
from dronewrapper.msgs.mission import MissionControl
from dronewrapper.runtime.errors import ServiceError
from dronewrapper_bridge_base.operation import Steps
from dronewrapper_bridge_tello import missions
from dronewrapper_bridge_tello.flight import MAX_TIMEOUT_S, checked, failed


class ActionPort(missions.MissionPort, Protocol):
    """What go-to, return and a mission's start use of the core besides the mission side's
    (:class:`~.missions.MissionPort`): whether the Tello is connected."""

    connected: bool


def _ready(core: ActionPort, what: str) -> flight.FlightResult | None:
    if not core.connected:
        return failed(flight.NOT_READY, "the Tello is not connected (no state string)")
    if core.telemetry.landed.state != LANDED_STATE_IN_AIR:
        return failed(flight.REFUSED, f"{what} refused: not flying (take off first)", what)
    core.failsafe.on_takeoff_or_land()  # the bridge flies it: no commander steers, none lost
    return None


def goto_point(core: ActionPort, request: flight.GotoRequest) -> Steps:
    """Fly to (x, y, z) m from the take-off point with ``go`` moves."""
    timeout = checked("timeout", request.timeout, 0.0, MAX_TIMEOUT_S)
    checked("tolerance", request.tolerance, 0.0, 100.0)
    refusal = _ready(core, "goto")
    if refusal is not None:
        return refusal
    if request.geodetic:
        return failed(flight.NO_HOME, "the Tello has no GPS: home has no latitude and longitude")
    target = (request.x, request.y, request.z)
    try:
        env.check_position(core.missions.envelope, *target)
    except EnvelopeError as exc:
        return failed(flight.REFUSED, f"goto refused: {exc}", "goto")
    deadline = core.now + timeout
    core.missions.paused = False
    arrived = yield from missions.fly_to(core, target)
    position = core.telemetry.position_enu
    distance = math.dist(position, target) if position is not None else math.nan
    if not arrived:
        return failed(flight.REFUSED, "a go move was refused or the go-to was paused", "goto")
    if core.now > deadline:
        return failed(flight.TOO_LATE, f"there only after {timeout:g} s ({distance:.2f} m away)")
    return flight.FlightResult(success=True, message=f"at the point: {distance:.2f} m away")


def return_home(core: ActionPort, request: flight.ReturnRequest) -> Steps:
    """Fly home at the current height and land; done on the ground."""
    checked("timeout", request.timeout, 0.0, MAX_TIMEOUT_S)
    refusal = _ready(core, "return")
    if refusal is not None:
        return refusal
    core.missions.paused = False
    arrived = yield from missions.fly_home(core)
    if not arrived:
        return failed(flight.REFUSED, "a go move home was refused", "return")
    return flight.FlightResult(success=True, message="returned: on the ground")


def mission_action(core: ActionPort, request: flight.MissionRequest) -> Steps:
    """Start or resume the mission's moves (in the background), or pause after the current
    move; the control's refusals as a failure."""
    checked("timeout", request.timeout, 0.0, MAX_TIMEOUT_S)
    refusal = _ready(core, request.action)
    if refusal is not None:
        return refusal
    action = "start" if request.action == "resume" else request.action
    try:
        reply = yield from missions.control(core, MissionControl(action=action))
    except ServiceError as exc:
        return failed(flight.REFUSED, exc.message, request.action)
    return flight.FlightResult(success=reply.success, message=reply.message)
