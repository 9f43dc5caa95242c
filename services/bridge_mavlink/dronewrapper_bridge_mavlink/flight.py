"""Take-off and landing, each one waiting operation flown the autopilot's way (pure).

- take-off, PX4: OFFBOARD (the stream primed for > ``offboard_prime_s`` first), the bridge's
  own hold at the ground (:meth:`~dronewrapper_bridge_base.guided_failsafe.Failsafe.hold_at`),
  arm, the own hold moved ``height`` m up; ArduPilot: GUIDED, arm, MAV_CMD_NAV_TAKEOFF. Then
  the climb is watched until within ``tolerance`` of the height: it fails when the autopilot
  disarms or leaves the mode it was put in, or the ``timeout`` passes (then the aircraft holds
  where it is: the climb stops). Already flying: done at once, nothing sent.
- landing: LAND here, then wait until on the ground and disarmed.

Each returns a :class:`~dronewrapper.msgs.flight.FlightResult` (a failure says which step and
why); a bad request is a ``ValueError``. Heights in metres above the take-off point (local ENU
z, origin where the autopilot started), time the core's (monotonic s). The core is seen as
:class:`FlightPort` shows it.
"""

from __future__ import annotations

import functools
import logging
import math
from collections.abc import Generator, Sequence
from typing import Any, Protocol

from dronewrapper.msgs import flight
from dronewrapper.msgs.mavros import (
    LANDED_STATE_IN_AIR,
    LANDED_STATE_TAKEOFF,
    SEVERITY_WARNING,
    CommandBool,
    CommandTOL,
    SetMode,
)
from dronewrapper.msgs.mavros import StatusText as StatusTextMsg
from dronewrapper_bridge_base.flight_request import checked, failed, took_off
from dronewrapper_bridge_base.guided_flight import landed
from dronewrapper_bridge_base.guided_takeoff import MAX_TIMEOUT_S, takeoff_start
from dronewrapper_bridge_base.operation import Steps
from dronewrapper_bridge_mavlink import operations as ops
from dronewrapper_bridge_mavlink.modes import AUTOPILOT_ARDUPILOT, AUTOPILOT_PX4, GUIDED_MODE
from dronewrapper_bridge_mavlink.setpoints import hold_target
from dronewrapper_bridge_mavlink.telemetry import Telemetry


class Texts(Protocol):
    """The texts heard (each with its arrival, monotonic s), the bridge's own among them."""

    @property
    def recent_texts(self) -> Sequence[tuple[float, StatusTextMsg]]: ...


class Located(Protocol):
    """The telemetry (local position ENU m)."""

    telemetry: Telemetry


log = logging.getLogger("bridge_mavlink")


class FlightPort(ops.OperationPort, Texts, Protocol):
    """What take-off and landing use of the core besides the operations they run
    (:class:`~.operations.OperationPort`) and the texts heard: whether the autopilot is
    connected, and the bridge's own hold where the aircraft is (``hold_here``)."""

    connected: bool

    def hold_here(self) -> None: ...


def takeoff_to(core: FlightPort, request: flight.TakeoffRequest) -> Steps:
    """Take off to ``request.height`` m above the take-off point (see module docstring)."""
    answer = functools.partial(takeoff_answer, core)
    plan = takeoff_start(core, request, answer, core.missions.refuse_takeoff)
    if isinstance(plan, flight.FlightResult):
        return plan
    autopilot = core.autopilot or AUTOPILOT_PX4
    mode = GUIDED_MODE[autopilot]
    if autopilot == AUTOPILOT_ARDUPILOT:
        steps: list[tuple[str, Any, Any]] = [
            (f"set_mode {mode}", ops.set_mode, SetMode(custom_mode=mode)),
            ("arming", ops.arming, CommandBool(value=True)),
            ("takeoff", ops.takeoff, CommandTOL.takeoff(plan.height, plan.yaw)),
        ]
    else:
        steps = [
            (f"set_mode {mode}", ops.set_mode, SetMode(custom_mode=mode)),
            ("arming", ops.arming, CommandBool(value=True)),
        ]
    for step, operation, step_request in steps:
        reply = yield from operation(core, step_request)
        if not (reply.mode_sent if isinstance(step_request, SetMode) else reply.success):
            core.failsafe.release_hold()
            return failed(flight.REFUSED, reply.message, step, reply.result)
        if autopilot != AUTOPILOT_ARDUPILOT:  # in OFFBOARD: hold the ground, then the height
            z = plan.start_z if step != "arming" else plan.target_z
            core.failsafe.hold_at(hold_target((plan.x, plan.y, z), plan.yaw))
    log.info("takeoff: %s, armed, climbing to %.2f m", mode, plan.target_z)
    outcome = yield from climb(
        core, mode, plan.target_z, plan.tolerance, plan.deadline, plan.timeout
    )
    if outcome is not None:
        if autopilot != AUTOPILOT_ARDUPILOT and outcome.failure == flight.REFUSED:
            core.failsafe.release_hold()
        if outcome.failure == flight.TOO_LATE:
            core.hold_here()  # the take-off ends here: the climb must not go on
        return outcome
    position = core.telemetry.position_enu
    return took_off(position[2] if position else math.nan, plan.start_z, plan.height)


def takeoff_answer(core: FlightPort) -> flight.FlightResult | None:
    """A take-off's answer before anything is sent: refused while the autopilot is not
    connected, done while it flies; None when the take-off goes on."""
    if not core.connected:
        return failed(flight.NOT_READY, "the autopilot is not connected (no heartbeat)")
    if core.ext.landed_state in (LANDED_STATE_IN_AIR, LANDED_STATE_TAKEOFF):
        return flight.FlightResult(
            success=True,
            message=f"already flying ({altitude_text(core)}): nothing done; a position "
            "setpoint changes the altitude",
        )
    return None


def climb(
    core: FlightPort, mode: str, target_z: float, tolerance: float, deadline: float, timeout: float
) -> Generator[float, None, flight.FlightResult | None]:
    """Wait until the local z is within ``tolerance`` of ``target_z`` (m): None, or the
    failure (disarmed, left ``mode``, ``deadline`` passed)."""
    seen_armed = seen_mode = False
    while True:
        state = core.heartbeat_state
        if state is not None:
            seen_armed |= state.armed
            seen_mode |= state.mode == mode
            if seen_armed and not state.armed:
                return failed(flight.REFUSED, f"the autopilot disarmed{last_text(core)}", "takeoff")
            if seen_mode and state.mode != mode:
                text = f"the autopilot left {mode} for {state.mode}{last_text(core)}"
                return failed(flight.REFUSED, text, "takeoff")
        position = core.telemetry.position_enu
        if position is not None and position[2] >= target_z - tolerance:
            return None
        if core.now >= deadline:
            return failed(
                flight.TOO_LATE,
                f"altitude {target_z:.2f} m not reached within {timeout:g} s (now "
                f"{altitude_text(core)}, "
                f"mode {state.mode if state else '?'}, armed {state.armed if state else '?'})",
            )
        yield deadline


def land_here(core: FlightPort, request: flight.LandRequest) -> Steps:
    """Land where the aircraft is; done once on the ground and disarmed."""
    timeout = checked("timeout", request.timeout, 0.0, MAX_TIMEOUT_S)
    if not core.connected:
        return failed(flight.NOT_READY, "the autopilot is not connected (no heartbeat)")
    if landed(core):
        return flight.FlightResult(success=True, message="already on the ground and disarmed")
    deadline = core.now + timeout
    reply = yield from ops.land(core, CommandTOL.land())
    if not reply.success:
        return failed(flight.REFUSED, reply.message, "land", reply.result)
    log.info("land: landing from %s", altitude_text(core))
    while not landed(core):
        if core.now >= deadline:
            state = core.heartbeat_state
            return failed(
                flight.TOO_LATE,
                f"not on the ground and disarmed in time (now {altitude_text(core)}, "
                f"landed_state {core.ext.landed_state}, armed {state.armed if state else '?'})",
            )
        yield deadline
    return flight.FlightResult(success=True, message="on the ground and disarmed")


def altitude_text(core: Located) -> str:
    position = core.telemetry.position_enu
    return "no position" if position is None else f"z={position[2]:.2f} m"


def last_text(core: Texts) -> str:
    """`` (the autopilot's latest warning)`` or ``""``."""
    for _, text in reversed(core.recent_texts):
        if text.severity <= SEVERITY_WARNING and text.header.frame_id != "bridge":
            return f" ({text.text})"
    return ""
