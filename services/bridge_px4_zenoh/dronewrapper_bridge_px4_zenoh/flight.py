"""Take-off, landing, go-to and return over PX4's Zenoh, each one waiting operation (pure),
answered with a :class:`~dronewrapper.msgs.flight.FlightResult` as on the other bridges:

- take-off: refused (``not_ready``) while PX4's vehicle_status says its preflight checks do not
  pass; else OFFBOARD (primed), the bridge's own hold at the ground, arm, the hold moved
  ``height`` m up; done within ``tolerance``; fails when PX4 disarms or leaves OFFBOARD, or
  at ``timeout`` (then it holds where it is). Already flying: done at once, nothing sent.
- landing: NAV_LAND here; done on the ground and disarmed.
- go-to: refused on the ground or outside the envelope; OFFBOARD and the bridge's own hold at
  the point (ENU m from home, home being PX4's local origin); done within ``tolerance``.
- return: refused on the ground; PX4's RTL; done on the ground and disarmed.

A go-to or return whose request names its commander's process (``watch``) is watched
(:mod:`.watch`): once a go-to has ended and that process has stopped beating, the bridge
returns or lands as for a lost commander.

Heights and points in metres (local ENU), time the core's (monotonic s). The request checks
and result shapes are those of bridge_mavlink's ``flight`` and ``actions``. The core is seen as
:class:`FlightPort` shows it.
"""

from __future__ import annotations

import functools
import logging
import math
from collections.abc import Generator
from typing import Any, Protocol

from dronewrapper.msgs import flight
from dronewrapper.msgs.mavros import (
    LANDED_STATE_IN_AIR,
    LANDED_STATE_TAKEOFF,
    CommandBool,
    CommandTOL,
    SetMode,
)
from dronewrapper_bridge_base.flight_request import checked, failed, goto_target, took_off
from dronewrapper_bridge_base.guided_failsafe import hold_target
from dronewrapper_bridge_base.guided_flight import flying, landed, returned
from dronewrapper_bridge_base.guided_takeoff import MAX_TIMEOUT_S, takeoff_start
from dronewrapper_bridge_base.operation import Steps
from dronewrapper_bridge_px4_zenoh import commands as cmds
from dronewrapper_bridge_px4_zenoh import envelope_rules as rules
from dronewrapper_bridge_px4_zenoh import operations as ops
from dronewrapper_bridge_px4_zenoh import watch

log = logging.getLogger("bridge_px4_zenoh")
NOT_CONNECTED = "PX4 is not connected (no sample on its Zenoh keys)"


class FlightPort(ops.OperationPort, watch.WatchPort, Protocol):
    """What the flight operations use of the core besides the operations they run
    (:class:`~.operations.OperationPort`), the watch (:class:`~.watch.WatchPort`) and a
    return's wait: whether PX4 is heard, its latest vehicle_status (None before any), the
    local position (ENU m) and yaw (ENU rad), the bridge's own hold where it is."""

    connected: bool
    status: dict[str, Any] | None
    position_enu: tuple[float, float, float] | None
    yaw_enu: float

    def hold_here(self) -> None: ...


def takeoff_to(core: FlightPort, request: flight.TakeoffRequest) -> Steps:
    """Take off to ``request.height`` m above the take-off point (see module docstring)."""
    refuse = functools.partial(rules.refuse_takeoff, core)
    plan = takeoff_start(core, request, functools.partial(takeoff_answer, core), refuse)
    if isinstance(plan, flight.FlightResult):
        return plan
    reply = yield from ops.set_mode(core, SetMode(custom_mode=ops.GUIDED))
    if not reply.mode_sent:
        return failed(flight.REFUSED, reply.message, f"set_mode {ops.GUIDED}", reply.result)
    core.failsafe.hold_at(hold_target((plan.x, plan.y, plan.start_z), plan.yaw))
    armed = yield from ops.arming(core, CommandBool(value=True))
    if not armed.success:
        core.failsafe.release_hold()
        return failed(flight.REFUSED, armed.message, "arming", armed.result)
    target = (plan.x, plan.y, plan.target_z)
    core.failsafe.hold_at(hold_target(target, plan.yaw))
    log.info("takeoff: OFFBOARD, armed, climbing to %.2f m", plan.target_z)
    outcome = yield from wait_at(
        core, target, plan.tolerance, plan.deadline, "takeoff", z_only=True
    )
    if outcome is not None:
        if outcome.failure == flight.TOO_LATE:
            core.hold_here()
        else:
            core.failsafe.release_hold()
        return outcome
    position = core.position_enu
    return took_off(position[2] if position else math.nan, plan.start_z, plan.height)


def takeoff_answer(core: FlightPort) -> flight.FlightResult | None:
    """A take-off's answer before anything is sent: refused while PX4 is not connected or its
    preflight checks do not pass (vehicle_status), done while it flies; None when the take-off
    goes on."""
    if not core.connected:
        return failed(flight.NOT_READY, NOT_CONNECTED)
    if core.ext.landed_state in (LANDED_STATE_IN_AIR, LANDED_STATE_TAKEOFF):
        return flight.FlightResult(success=True, message="already flying: nothing done")
    if core.status is not None and not core.status["pre_flight_checks_pass"]:
        return failed(flight.NOT_READY, "PX4's preflight checks do not pass yet (vehicle_status)")
    return None


def wait_at(
    core: FlightPort,
    target: tuple[float, float, float],
    tolerance: float,
    deadline: float,
    step: str,
    *,
    z_only: bool = False,
) -> Generator[float, None, flight.FlightResult | None]:
    """Wait until within ``tolerance`` m of ``target`` (only its height with ``z_only``):
    None, or the failure (PX4 disarmed or left OFFBOARD after showing it armed in OFFBOARD:
    vehicle_status, ~2 Hz, may show an accepted arming later than its ack; ``deadline``
    passed)."""
    seen_armed = seen_mode = False
    while True:
        position = core.position_enu
        if position is not None:
            distance = abs(target[2] - position[2]) if z_only else math.dist(position, target)
            if distance <= tolerance:
                return None
        state = core.heartbeat_state
        if state is not None:
            seen_armed |= state.armed
            seen_mode |= state.mode == ops.GUIDED
            if seen_armed and not state.armed:
                return failed(flight.REFUSED, "PX4 disarmed", step)
            if seen_mode and state.mode != ops.GUIDED:
                return failed(flight.REFUSED, f"PX4 left {ops.GUIDED} for {state.mode}", step)
        if core.now >= deadline:
            where = "no position" if position is None else f"z={position[2]:.2f} m"
            return failed(
                flight.TOO_LATE, f"not within {tolerance:g} m of the target in time ({where})"
            )
        yield deadline


def land_here(core: FlightPort, request: flight.LandRequest) -> Steps:
    """Land where the aircraft is; done once on the ground and disarmed."""
    timeout = checked("timeout", request.timeout, 0.0, MAX_TIMEOUT_S)
    if not core.connected:
        return failed(flight.NOT_READY, NOT_CONNECTED)
    if landed(core):
        return flight.FlightResult(success=True, message="already on the ground and disarmed")
    deadline = core.now + timeout
    core.failsafe.release_hold()
    reply = yield from ops.land(core, CommandTOL.land())
    if not reply.success:
        return failed(flight.REFUSED, reply.message, "land", reply.result)
    return (yield from wait_landed(core, deadline, timeout))


def wait_landed(core: FlightPort, deadline: float, timeout: float) -> Steps:
    while not landed(core):
        if core.now >= deadline:
            return failed(flight.TOO_LATE, f"not on the ground and disarmed after {timeout:g} s")
        yield deadline
    return flight.FlightResult(success=True, message="on the ground and disarmed")


def goto_point(core: FlightPort, request: flight.GotoRequest) -> Steps:
    """Fly to the point and hold there (see module docstring)."""
    timeout = checked("timeout", request.timeout, 0.0, MAX_TIMEOUT_S)
    tolerance = checked("tolerance", request.tolerance, 0.0, 100.0)
    if not core.connected:
        return failed(flight.NOT_READY, NOT_CONNECTED)
    if not flying(core):
        return failed(flight.REFUSED, "goto refused: not flying (take off first)", "goto")
    target = goto_target(core.envelope, request)
    if isinstance(target, flight.FlightResult):
        return target
    deadline = core.now + timeout
    if ops.shown_mode(core) != ops.GUIDED:
        reply = yield from ops.set_mode(core, SetMode(custom_mode=ops.GUIDED))
        if not reply.mode_sent:
            return failed(flight.REFUSED, reply.message, f"set_mode {ops.GUIDED}", reply.result)
    core.failsafe.hold_at(hold_target(target, core.yaw_enu))
    watch.start(core, "goto", request.watch)
    try:
        outcome = yield from wait_at(core, target, tolerance, deadline, "goto")
    finally:
        core.unattended.ended(core.now)  # reached, given up or cancelled: the go-to is over
    if outcome is not None:
        if outcome.failure == flight.TOO_LATE:
            core.hold_here()
        return outcome
    distance = math.dist(core.position_enu, target) if core.position_enu else math.nan
    return flight.FlightResult(success=True, message=f"at the point: {distance:.2f} m away")


def return_home(core: FlightPort, request: flight.ReturnRequest) -> Steps:
    """PX4's return (RTL); done on the ground, disarmed."""
    timeout = checked("timeout", request.timeout, 0.0, MAX_TIMEOUT_S)
    if not core.connected:
        return failed(flight.NOT_READY, NOT_CONNECTED)
    if not flying(core):
        return failed(flight.REFUSED, "return refused: not flying (take off first)", "return")
    deadline = core.now + timeout
    core.failsafe.release_hold()
    for mode in (ops.RETURN_MODE, ops.LAND_MODE):
        core.failsafe.on_mode_requested(mode, core.now)
    result, message = yield from ops.command(
        core, cmds.vehicle_command(cmds.NAV_RETURN_TO_LAUNCH, **ops.target(core))
    )
    if result != ops.ACCEPTED:
        return failed(flight.REFUSED, message, "return", max(result, 0))
    core.mode_entered(ops.RETURN_MODE)
    watch.start(core, "return", request.watch)
    modes = (ops.RETURN_MODE, ops.LAND_MODE)
    return (yield from returned(core, modes, deadline, timeout, "PX4"))
