"""What the flight operations of both PX4-capable bridges (MAVLink, PX4 over Zenoh) read and wait
on, over their :class:`~dronewrapper_bridge_base.guided_core.GuidedCore` (each through the small
protocol it reads): whether the aircraft
flies (:func:`flying`) or is down (:func:`landed`), the end of a return (:func:`returned`), and
a command that puts the autopilot in a mode (:func:`mode_command`), the failsafe's own
(:func:`failsafe_request`) among them.

A command's exchange is the bridge's own: a generator of resume times (monotonic s) returning
(result, explanation), the result a MAV_RESULT (PX4's vehicle_command_ack uses the same codes).
"""

from __future__ import annotations

import logging
from collections.abc import Generator
from typing import Protocol

from dronewrapper.msgs.flight import REFUSED, TOO_LATE, FlightResult
from dronewrapper.msgs.mavros import LANDED_STATE_ON_GROUND, ExtendedState, State
from dronewrapper_bridge_base.core_view import Clock
from dronewrapper_bridge_base.flight_request import failed
from dronewrapper_bridge_base.guided_failsafe import Failsafe
from dronewrapper_bridge_base.operation import Steps
from dronewrapper_bridge_base.unattended import Unattended

CommandSteps = Generator[float, None, tuple[int, str]]
"""A command's exchange: resume times (monotonic s), then (result, explanation)."""
ACCEPTED = 0  # MAV_RESULT_ACCEPTED, VehicleCommandAck's VEHICLE_CMD_RESULT_ACCEPTED


class Airborne(Protocol):
    """What :func:`flying` reads of a core: its failsafe (armed, airborne)."""

    @property
    def failsafe(self) -> Failsafe: ...


class Grounded(Protocol):
    """What :func:`landed` reads of a core: the last State heard (None before any) and the
    landed state."""

    @property
    def heartbeat_state(self) -> State | None: ...
    @property
    def ext(self) -> ExtendedState: ...


class Returning(Grounded, Clock, Protocol):
    """What :func:`returned` reads of a core besides :class:`Grounded` and its time: the
    unattended rule (cleared once down)."""

    @property
    def unattended(self) -> Unattended: ...


class ModeCore(Clock, Protocol):
    """What :func:`mode_command` reads and calls of a core besides its time."""

    @property
    def failsafe(self) -> Failsafe: ...
    def mode_entered(self, mode: str) -> None: ...  # the autopilot accepted a command into it


def flying(core: Airborne) -> bool:
    """Armed and in the air (per the landed state)."""
    return core.failsafe.airborne and core.failsafe.armed


def landed(core: Grounded) -> bool:
    """On the ground and disarmed."""
    state = core.heartbeat_state
    return core.ext.landed_state == LANDED_STATE_ON_GROUND and state is not None and not state.armed


def returned(
    core: Returning, modes: tuple[str, str], deadline: float, timeout: float, who: str
) -> Steps:
    """Wait until a return started in ``modes[0]`` (``modes[1]``: the landing it ends in) is on
    the ground and disarmed, by ``deadline`` (monotonic s; ``timeout`` s as asked); refused when
    ``who`` (the autopilot) leaves both modes while armed."""
    while not landed(core):
        hb = core.heartbeat_state
        if hb is not None and hb.armed and hb.mode not in modes:
            return failed(REFUSED, f"{who} left {modes[0]} for {hb.mode}", "return")
        if core.now >= deadline:
            return failed(TOO_LATE, f"not on the ground and disarmed after {timeout:g} s")
        yield deadline
    core.unattended.clear()
    return FlightResult(success=True, message="returned: on the ground and disarmed")


def mode_command(core: ModeCore, mode: str, sent: CommandSteps) -> CommandSteps:
    """Run ``sent``, a command that puts the autopilot in ``mode``: the failsafe knows first
    that the bridge asked for ``mode`` (no pilot's change), the core as soon as it is
    accepted (its ``mode_entered``)."""
    core.failsafe.on_mode_requested(mode, core.now)
    result, message = yield from sent
    if result == ACCEPTED:
        core.mode_entered(mode)
    return result, message


def failsafe_request(
    core: ModeCore, action: str, mode: str, sent: CommandSteps, who: str, log: logging.Logger
) -> Generator[float, None, int]:
    """The failsafe's own request ``action`` (``land`` or ``return``): ``sent`` puts the
    autopilot (``who``, as the log names it) in ``mode``; nobody waits for it, the outcome is
    logged. Returns the command's result."""
    result, message = yield from mode_command(core, mode, sent)
    if result == ACCEPTED:
        log.warning("failsafe %s: accepted by %s", action, who)
    else:
        log.error("failsafe %s refused: %s", action, message)
    return result
