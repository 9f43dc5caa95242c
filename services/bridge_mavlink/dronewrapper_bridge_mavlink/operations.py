"""Service calls that wait for the autopilot, as pure operations the core advances.

Each operation is a generator over the core as :class:`OperationPort` shows it (the parts an
operation uses, nothing else): it reads ``core.now`` (set by the caller of every core entry
point), sends through the core's ``commands``, and yields the time (monotonic s) it wants to be
resumed at the latest; the core resumes it whenever a message or a tick arrives, so
every wait is a loop that re-checks its condition. Its return value is the service reply; an
exception it raises (``ValueError`` for a bad request, ``ServiceError``) is the call's error.
No sockets, threads or clock here: the node waits on
:attr:`dronewrapper_bridge_base.operation.Operation.done`.

The rules they carry: a take-off while flying does nothing; PX4's OFFBOARD is asked for only
after > ``offboard_prime_s`` of streaming; PX4's DO_SET_MODE is answered by its second ack (a
refusal with the autopilot's STATUSTEXT reason), and a mode acked only once must show in
HEARTBEAT; PX4 integer parameters travel as their bytes (param_values.py).
"""

from __future__ import annotations

import logging
import math
from collections.abc import Generator
from typing import Protocol

from pymavlink.dialects.v20 import common as mavlink

from dronewrapper.msgs import mavros
from dronewrapper_bridge_base.envelope_state import EnvelopeState
from dronewrapper_bridge_base.flight_request import land_point, takeoff_command
from dronewrapper_bridge_base.guided_flight import (
    Grounded,
    ModeCore,
    failsafe_request,
    mode_command,
)
from dronewrapper_bridge_base.offboard_prime import PrimingCore, prime
from dronewrapper_bridge_base.operation import Steps
from dronewrapper_bridge_mavlink import commands as cmds
from dronewrapper_bridge_mavlink.command_exchange import Commands
from dronewrapper_bridge_mavlink.config import Config
from dronewrapper_bridge_mavlink.modes import (
    AUTOPILOT_ARDUPILOT,
    AUTOPILOT_PX4,
    GUIDED_MODE,
    HOLD_MODE,
    LAND_MODE,
    RETURN_MODE,
    is_guided,
    set_mode_params,
)
from dronewrapper_bridge_mavlink.telemetry import Telemetry

log = logging.getLogger("bridge_mavlink")

ACCEPTED = mavlink.MAV_RESULT_ACCEPTED


class Heard(Protocol):
    """The autopilot as heard: its kind (``""`` before a heartbeat) and the State its last
    HEARTBEAT showed (None before any; an accepted mode command changes it at once)."""

    autopilot: str
    heartbeat_state: mavros.State | None


class Commanding(Protocol):
    """What a plain command uses of the core: its command exchange (:class:`Commands`)."""

    commands: Commands


class FailsafePort(Heard, Commanding, ModeCore, Protocol):
    """What the failsafe's own request uses: the autopilot as heard, the command exchange,
    the failsafe and the mode accepted (``mode_entered``)."""


class OperationPort(FailsafePort, Grounded, PrimingCore, Protocol):
    """What the operations here read and call of the core (``now`` monotonic s) besides
    :class:`FailsafePort`: the landed state, the failsafe's priming, the config, the
    telemetry (the take-off altitude), the envelope's refusals (the mission state as its
    :class:`EnvelopeState`) and whether the autopilot is heard (``require_connected``)."""

    config: Config
    telemetry: Telemetry

    @property
    def missions(self) -> EnvelopeState: ...

    def require_connected(self) -> str: ...


# ---------------------------------------------------------------- commands


def exchange(
    core: Commanding, command: int, *params: float, expected_acks: int = 1
) -> Generator[float, None, tuple[cmds.PendingCommand, str]]:
    """A COMMAND_LONG until its final ack, by the core's :class:`~.command_exchange.Commands`:
    the finished command and an explanation."""
    return (yield from core.commands.exchange(command, *params, expected_acks=expected_acks))


def command(core: Commanding, command: int, *params: float) -> Generator[float, None, tuple]:
    """:func:`exchange` for a command acked once: (MAV_RESULT, explanation)."""
    pending, message = yield from exchange(core, command, *params)
    return pending.result, message


def arming(core: OperationPort, request: mavros.CommandBool) -> Steps:
    """ARMING: MAV_CMD_COMPONENT_ARM_DISARM; the reply carries the real ack."""
    core.require_connected()
    result, message = yield from command(
        core, mavlink.MAV_CMD_COMPONENT_ARM_DISARM, 1.0 if request.value else 0.0
    )
    return mavros.CommandBoolResult(success=result == ACCEPTED, result=result, message=message)


def takeoff(core: OperationPort, request: mavros.CommandTOL) -> Steps:
    """TAKEOFF: MAV_CMD_NAV_TAKEOFF to ``altitude`` m above the take-off point; while flying
    it does nothing (a second take-off must not send the vehicle to a new height)."""
    autopilot = core.require_connected()
    height, yaw_deg = takeoff_command(request.altitude, request.yaw)
    if core.ext.landed_state == mavros.LANDED_STATE_IN_AIR:
        return mavros.CommandTOLResult(success=True, result=ACCEPTED, message="already flying")
    core.missions.refuse_takeoff(height)  # above the envelope: refused, the limit named
    if autopilot == AUTOPILOT_ARDUPILOT:
        altitude = height if not math.isnan(height) else 2.5
    elif math.isnan(height):
        altitude = math.nan
    else:
        altitude = core.telemetry.takeoff_altitude_amsl(height)
    core.failsafe.on_mode_requested("AUTO.TAKEOFF", core.now)
    core.failsafe.on_mode_requested(HOLD_MODE[autopilot], core.now)
    core.failsafe.on_takeoff_requested(core.now)  # no priming, no hold into the climb
    result, message = yield from command(
        core,
        mavlink.MAV_CMD_NAV_TAKEOFF,
        request.min_pitch,
        0,
        0,
        yaw_deg,
        math.nan,
        math.nan,
        altitude,
    )
    if result == ACCEPTED and autopilot == AUTOPILOT_PX4:
        core.mode_entered("AUTO.TAKEOFF")  # ArduCopter climbs in GUIDED itself
    if not math.isnan(height) and math.isnan(altitude):
        message += " (no home altitude known: the autopilot's default take-off altitude)"
    return mavros.CommandTOLResult(success=result == ACCEPTED, result=result, message=message)


def land(core: OperationPort, request: mavros.CommandTOL) -> Steps:
    """LAND: MAV_CMD_NAV_LAND here (NaN lat/lon: current position, no GPS needed)."""
    autopilot = core.require_connected()
    lat, lon = land_point(request.latitude, request.longitude)
    sent = command(core, mavlink.MAV_CMD_NAV_LAND, 0, 0, 0, math.nan, lat, lon, math.nan)
    result, message = yield from mode_command(core, LAND_MODE[autopilot], sent)
    return mavros.CommandTOLResult(success=result == ACCEPTED, result=result, message=message)


def failsafe_action(core: FailsafePort, action: str) -> Steps:
    """The failsafe's own request (``land`` or ``return``); nobody waits for it."""
    autopilot = core.autopilot or AUTOPILOT_PX4
    if action == "land":
        nan = math.nan
        mode = LAND_MODE[autopilot]
        sent = command(core, mavlink.MAV_CMD_NAV_LAND, 0, 0, 0, nan, nan, nan, nan)
    else:
        mode, sent = RETURN_MODE[autopilot], command(core, mavlink.MAV_CMD_NAV_RETURN_TO_LAUNCH)
    return (yield from failsafe_request(core, action, mode, sent, "the autopilot", log))


# ---------------------------------------------------------------- modes


def set_mode(core: OperationPort, request: mavros.SetMode) -> Steps:
    """SET_MODE by name; replies once the autopilot has really entered or refused it.

    PX4: OFFBOARD is preceded by > offboard_prime_s of streaming (priming); DO_SET_MODE is
    acknowledged twice and the second ack (the commander's) is the answer, a refusal with
    PX4's STATUSTEXT reason; with no second ack the mode must show in HEARTBEAT within
    mode_confirm_timeout. ArduPilot: one ack, and ACCEPTED means the mode is entered; no
    priming (a hold at the ground would override its take-off). An entered mode is known
    at once (failsafe, State), not at the next 1 Hz heartbeat.
    """
    autopilot = core.require_connected()
    params = set_mode_params(autopilot, request.custom_mode)  # ValueError lists valid modes
    px4 = autopilot == AUTOPILOT_PX4
    primed = px4 and params.name == GUIDED_MODE[AUTOPILOT_PX4]
    if primed:
        yield from prime(core)
    guided = is_guided(params.name)  # no guided mode while outside the envelope
    core.missions.refuse_mode(params.name, guided=guided)
    core.failsafe.on_mode_requested(params.name, core.now)
    pending, message = yield from exchange(
        core,
        mavlink.MAV_CMD_DO_SET_MODE,
        params.param1,
        params.param2,
        params.param3,
        expected_acks=2 if px4 else 1,
    )
    result = pending.result
    if result == ACCEPTED and not pending.confirmed:
        timeout = core.config.mode_confirm_timeout
        deadline = core.now + timeout
        while shown_mode(core) != params.name and core.now < deadline:
            yield deadline
        seen = shown_mode(core)
        if seen == params.name:
            message += " (confirmed by HEARTBEAT)"
        else:
            result = mavlink.MAV_RESULT_FAILED
            message = (
                f"DO_SET_MODE {params.name}: acknowledged once, but the autopilot is still "
                f"in {seen or 'an unknown mode'} after {timeout:g} s"
            )
    if result == ACCEPTED:
        core.mode_entered(params.name)
    # the stream goes on only if the bridge holds OFFBOARD now
    core.failsafe.end_priming(core.now, engage=primed and result == ACCEPTED)
    return mavros.SetModeResult(mode_sent=result == ACCEPTED, result=result, message=message)


def shown_mode(core: Heard) -> str:
    """The mode the last HEARTBEAT showed (or an accepted command set), "" before any."""
    return core.heartbeat_state.mode if core.heartbeat_state else ""
