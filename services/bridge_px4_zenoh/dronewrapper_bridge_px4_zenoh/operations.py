"""Service calls that wait for PX4, as pure operations the core advances (see
:mod:`dronewrapper_bridge_base.operation`): vehicle commands on ``/fmu/in/vehicle_command``,
answered by ``/fmu/out/vehicle_command_ack``.

A command is written up to ``command_attempts`` times, ``command_ack_timeout`` s apart, until
an ack for the same command arrives or vehicle_status shows its effect (one exchange at a
time): with PX4's MAVLink link busy beside it, PX4's zenoh module was measured to publish no
ack for some commands it carried out. A mode is asked for with
``VEHICLE_CMD_SET_NAV_STATE``; an accepted one must show in vehicle_status within
``mode_confirm_timeout``. OFFBOARD is asked for only after > ``offboard_prime_s`` of
streaming (PX4 refuses it without a setpoint stream). The core is seen as :class:`CommandPort`
(a command's exchange) and :class:`OperationPort` (the operations) show it.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Callable, Generator, Sequence
from typing import Any, Protocol

from dronewrapper.msgs import mavros
from dronewrapper_bridge_base.core_view import CommandSlot
from dronewrapper_bridge_base.flight_request import land_point, takeoff_command
from dronewrapper_bridge_base.guided_flight import (
    Grounded,
    ModeCore,
    failsafe_request,
    mode_command,
)
from dronewrapper_bridge_base.offboard_prime import PrimingCore, prime
from dronewrapper_bridge_base.operation import Steps
from dronewrapper_bridge_px4_zenoh import commands as cmds
from dronewrapper_bridge_px4_zenoh import envelope_rules as rules
from dronewrapper_bridge_px4_zenoh import topics as t
from dronewrapper_bridge_px4_zenoh.config import Config
from dronewrapper_bridge_px4_zenoh.modes import mode_name, nav_state_of

log = logging.getLogger("bridge_px4_zenoh")

ACCEPTED = cmds.ACCEPTED
NO_ACK = -1
GUIDED, LAND_MODE, RETURN_MODE, HOLD_MODE = "OFFBOARD", "AUTO.LAND", "AUTO.RTL", "AUTO.LOITER"
NAMES = {
    cmds.ARM_DISARM: "ARM_DISARM",
    cmds.NAV_TAKEOFF: "NAV_TAKEOFF",
    cmds.NAV_LAND: "NAV_LAND",
    cmds.NAV_RETURN_TO_LAUNCH: "NAV_RETURN_TO_LAUNCH",
    cmds.SET_NAV_STATE: "SET_NAV_STATE",
}


class Heard(Protocol):
    """PX4 as its last vehicle_status showed it (State; None before any)."""

    heartbeat_state: mavros.State | None


class CommandPort(Heard, CommandSlot, ModeCore, Protocol):
    """What a vehicle command's exchange uses of the core besides its time, PX4 as heard,
    the one command slot, the failsafe and the mode accepted: the config (attempts, ack
    timeout), the writes to PX4, the acks heard (when, command, result; newest last), PX4's
    address (0 until vehicle_status names it)."""

    config: Config
    target_system: int
    target_component: int

    @property
    def acks(self) -> Sequence[tuple[float, int, int]]: ...

    def write(self, topic: t.Px4Topic, value: dict[str, Any]) -> None: ...


class OperationPort(CommandPort, PrimingCore, Grounded, rules.Enveloped, Protocol):
    """What the operations use of the core besides a command's exchange: priming, the
    landed state, the envelope's refusals, and whether PX4 is heard."""

    def require_connected(self) -> str: ...


def command(
    core: CommandPort, value: dict, shown: Callable[[], bool] | None = None
) -> Generator[float, None, tuple[int, str]]:
    """Write a VehicleCommand and wait for its ack: (result, explanation); ``NO_ACK`` when
    none came after every attempt. ``shown``: True once vehicle_status shows the command's
    effect (armed, the mode asked for): then it counts as accepted without an ack (PX4's
    module may publish a later ack in its place, measured beside a MAVLink link)."""
    config = core.config
    number = value["command"]
    name = NAMES.get(number, f"command {number}")
    while core.command_busy:
        yield core.now + 0.05
    core.take_command_slot()
    try:
        for _ in range(config.command_attempts):
            sent = core.now
            core.write(t.COMMAND, value)
            deadline = sent + config.command_ack_timeout
            while core.now < deadline:
                if shown is not None and shown():
                    return ACCEPTED, f"{name} accepted (no ack; vehicle_status shows it)"
                for at, acked, result in reversed(core.acks):
                    if at >= sent and acked == number and result != cmds.IN_PROGRESS:
                        text = cmds.result_text(result)
                        return result, f"{name} {text}" if result == ACCEPTED else (
                            f"{name} refused: {text}"
                        )
                yield deadline
        return NO_ACK, f"{name}: no vehicle_command_ack after {config.command_attempts} attempt(s)"
    finally:
        core.release_command_slot()


def target(core: CommandPort) -> dict[str, int]:
    """The system and component a vehicle command is for: PX4's own (its vehicle_status's,
    unless configured); 1, 1 before it is known."""
    return {
        "target_system": core.target_system or 1,
        "target_component": core.target_component or 1,
    }


def arming(core: OperationPort, request: mavros.CommandBool) -> Steps:
    """ARMING: VEHICLE_CMD_COMPONENT_ARM_DISARM; the reply carries PX4's ack."""
    core.require_connected()
    value = bool(request.value)
    result, message = yield from command(
        core, cmds.arm(value, **target(core)), lambda: armed(core) == value
    )
    return mavros.CommandBoolResult(
        success=result == ACCEPTED, result=max(result, 0), message=message
    )


def takeoff(core: OperationPort, request: mavros.CommandTOL) -> Steps:
    """TAKEOFF: VEHICLE_CMD_NAV_TAKEOFF to ``altitude`` m above PX4's local origin (NaN: PX4's
    MIS_TAKEOFF_ALT); while flying it does nothing."""
    core.require_connected()
    height, yaw_deg = takeoff_command(request.altitude, request.yaw)
    if core.ext.landed_state == mavros.LANDED_STATE_IN_AIR:
        return mavros.CommandTOLResult(success=True, result=ACCEPTED, message="already flying")
    rules.refuse_takeoff(core, height)  # above the envelope: refused, the limit named
    home = core.envelope.home_geo
    altitude = math.nan if math.isnan(height) or home is None else home[2] + height
    for mode in ("AUTO.TAKEOFF", HOLD_MODE):
        core.failsafe.on_mode_requested(mode, core.now)
    core.failsafe.on_takeoff_requested(core.now)  # no priming, no hold into the climb
    value = cmds.vehicle_command(
        cmds.NAV_TAKEOFF,
        request.min_pitch,
        0,
        0,
        yaw_deg,
        math.nan,
        math.nan,
        altitude,
        **target(core),
    )
    result, message = yield from command(core, value, lambda: shown_mode(core) == "AUTO.TAKEOFF")
    if result == ACCEPTED:
        core.mode_entered("AUTO.TAKEOFF")
    return mavros.CommandTOLResult(
        success=result == ACCEPTED, result=max(result, 0), message=message
    )


def land(core: OperationPort, request: mavros.CommandTOL) -> Steps:
    """LAND: VEHICLE_CMD_NAV_LAND here (NaN latitude/longitude: where it is)."""
    core.require_connected()
    lat, lon = land_point(request.latitude, request.longitude)
    value = cmds.vehicle_command(
        cmds.NAV_LAND, 0, 0, 0, math.nan, lat, lon, math.nan, **target(core)
    )
    sent = command(core, value, lambda: shown_mode(core) == LAND_MODE)
    result, message = yield from mode_command(core, LAND_MODE, sent)
    return mavros.CommandTOLResult(
        success=result == ACCEPTED, result=max(result, 0), message=message
    )


def failsafe_action(core: CommandPort, action: str) -> Steps:
    """The failsafe's own request (``land`` or ``return``); nobody waits for it."""
    mode = LAND_MODE if action == "land" else RETURN_MODE
    nan = math.nan
    value = (
        cmds.vehicle_command(cmds.NAV_LAND, 0, 0, 0, nan, nan, nan, nan, **target(core))
        if action == "land"
        else cmds.vehicle_command(cmds.NAV_RETURN_TO_LAUNCH, **target(core))
    )
    sent = command(core, value, lambda: shown_mode(core) == mode)
    return (yield from failsafe_request(core, action, mode, sent, "PX4", log))


def set_mode(core: OperationPort, request: mavros.SetMode) -> Steps:
    """SET_MODE by MAVROS name (OFFBOARD, AUTO.LOITER ...); replies once PX4 shows the mode
    in vehicle_status, or refused it. OFFBOARD is preceded by priming."""
    core.require_connected()
    mode = mode_name(nav_state_of(request.custom_mode))  # ValueError lists the modes
    primed = mode == GUIDED
    if primed:
        yield from prime(core)
    rules.refuse_mode(core, mode)  # no guided mode while outside the envelope
    core.failsafe.on_mode_requested(mode, core.now)
    result, message = yield from command(
        core,
        cmds.set_nav_state(nav_state_of(mode), **target(core)),
        lambda: shown_mode(core) == mode,
    )
    if result == ACCEPTED:
        deadline = core.now + core.config.mode_confirm_timeout
        while shown_mode(core) != mode and core.now < deadline:
            yield deadline
        if shown_mode(core) == mode:
            message += " (shown by vehicle_status)"
        else:
            result = cmds.FAILED
            message = (
                f"SET_NAV_STATE {mode}: accepted, but PX4 is still in "
                f"{shown_mode(core) or 'an unknown mode'} after "
                f"{core.config.mode_confirm_timeout:g} s"
            )
    core.failsafe.end_priming(core.now, engage=primed and result == ACCEPTED)
    return mavros.SetModeResult(
        mode_sent=result == ACCEPTED, result=max(result, 0), message=message
    )


def armed(core: Heard) -> bool:
    """Whether PX4's last vehicle_status showed it armed."""
    return core.heartbeat_state is not None and core.heartbeat_state.armed


def shown_mode(core: Heard) -> str:
    """The mode PX4's last vehicle_status showed, "" before any."""
    return core.heartbeat_state.mode if core.heartbeat_state else ""


def breach_action(core: OperationPort, action: str) -> Steps:
    """The envelope's action after a breach: ``land`` or ``return`` (the failsafe's own
    requests), or ``hold`` (AUTO.LOITER)."""
    if action in ("land", "return"):
        return (yield from failsafe_action(core, action))
    reply = yield from set_mode(core, mavros.SetMode(custom_mode=HOLD_MODE))
    return reply.result
