"""Service calls that wait for the Tello, as pure operations the core advances.

Each operation is a generator over the core as :class:`OperationPort` shows it: it
reads ``core.now`` (set by the caller of every core entry point), queues SDK commands on the
core, and yields the time (monotonic s) it wants to be resumed at the latest; the core resumes
it whenever a reply, a state string or a tick arrives, so every wait is a loop that re-checks
its condition. Its return value is the service reply; an exception it raises (``ValueError``
for a bad request, ``ServiceError``) is the call's error. No sockets, threads or clock here
(bridge_mavlink's operations.py is built the same way).

The rules they carry: one command in flight at a time (the Tello's replies carry no ids); a
quick command is re-sent after ``command_timeout`` up to ``command_attempts`` times, and after a
retried or unanswered one its stray replies get 0.3 s to arrive so a late ``ok`` is never taken
for the next command's answer; ``takeoff`` and ``land`` are sent once and wait for the Tello's
``ok``; a take-off while flying does nothing; a take-off whose ``ok`` was lost is confirmed by
the height; ``error ...`` replies are refusals with the Tello's text.
"""

from __future__ import annotations

import logging
import math
import re
from collections.abc import Generator
from typing import Any, Protocol

from dronewrapper.envelope import EnvelopeError, check_takeoff
from dronewrapper.msgs.mavros import (
    LANDED_STATE_IN_AIR,
    LANDED_STATE_ON_GROUND,
    CommandBool,
    CommandBoolResult,
    CommandTOL,
    CommandTOLResult,
    ParamGet,
    ParamGetResult,
    ParamSet,
    ParamSetResult,
    ParamValue,
    SetMode,
    SetModeResult,
)
from dronewrapper.runtime import ServiceError
from dronewrapper_bridge_base.core_view import Clock, CommandSlot
from dronewrapper_bridge_base.operation import Steps
from dronewrapper_bridge_tello.config import Config
from dronewrapper_bridge_tello.failsafe import Failsafe
from dronewrapper_bridge_tello.mission_state import TelloMissions
from dronewrapper_bridge_tello.replies import Pending, ReplyMatcher, is_ok
from dronewrapper_bridge_tello.telemetry import Telemetry
from dronewrapper_bridge_tello.video_demand import STREAMON

log = logging.getLogger("bridge_tello")


class Exchanging(Clock, CommandSlot, Protocol):
    """What :func:`exchange` uses of the core besides its time and the one command slot: the
    config (timeouts, attempts), the replies' matcher and the SDK command's send."""

    config: Config
    matcher: ReplyMatcher

    def send(self, text: str) -> None: ...


class OperationPort(Exchanging, Protocol):
    """What the operations here use of the core besides :class:`Exchanging`: the state
    strings heard (their count, the telemetry), the failsafe, the envelope (the mission
    state), the SDK mode and video replies, the State published."""

    states_received: int
    failsafe: Failsafe
    missions: TelloMissions
    telemetry: Telemetry

    def require_connected(self) -> None: ...
    def publish_state(self, *, force: bool = False) -> None: ...
    def in_sdk_mode(self) -> None: ...
    def restart_video(self) -> None: ...
    def video_answered(self, command: str, reply: str | None) -> None: ...


MAV_RESULT_ACCEPTED = 0
MAV_RESULT_DENIED = 2
RESULT_NO_REPLY = -1
BUSY_POLL_S = 0.05  # s between looks at a busy command slot
SETTLE_S = 0.3  # s stray replies of a retried or unanswered command may take

SDK_MODES = ("OFFBOARD", "GUIDED", "SDK")
HOVER_MODES = ("AUTO.LOITER", "HOLD", "LOITER", "POSCTL", "BRAKE")
LAND_MODES = ("AUTO.LAND", "LAND")
EMERGENCY_MODES = ("EMERGENCY",)
ALL_MODES = SDK_MODES + HOVER_MODES + LAND_MODES + EMERGENCY_MODES

# param id -> (read command, settable with "<command> <value>" in [lo, hi] or None)
PARAMS: dict[str, tuple[str, tuple[str, float, float] | None]] = {
    "SPEED": ("speed?", ("speed", 10.0, 100.0)),  # cm/s of the move commands
    "BATTERY": ("battery?", None),  # %
    "FLIGHT_TIME": ("time?", None),  # s of motor time
    "HEIGHT": ("height?", None),  # dm
    "TOF": ("tof?", None),  # mm
    "BARO": ("baro?", None),  # m
    "WIFI_SNR": ("wifi?", None),
    "SDK_VERSION": ("sdk?", None),
}
_NUMBER = re.compile(r"-?\d+(?:\.\d+)?")


# ---------------------------------------------------------------- commands


def exchange(
    core: Exchanging, text: str, *, timeout: float = 0.0, attempts: int = 0
) -> Generator[float, None, str | None]:
    """Send ``text`` and wait for its reply, re-sending it after ``timeout`` s (default
    ``command_timeout``) up to ``attempts`` times (default ``command_attempts``); the reply,
    or None when none came."""
    config = core.config
    pending = Pending(
        text,
        timeout=timeout or config.command_timeout,
        attempts=attempts or config.command_attempts,
    )
    while core.command_busy:
        yield core.now + BUSY_POLL_S
    core.take_command_slot()
    try:
        while True:
            if pending.due(core.now):
                core.matcher.sent(pending, core.now)
                core.send(text)
            if pending.finished(core.now):
                break
            yield pending.wake_at(core.now)
        if pending.sent > 1 or pending.reply is None:
            # give stray replies to the other sends their time, then forget them
            settle = core.now + min(SETTLE_S, config.command_timeout)
            while core.now < settle and core.matcher.waiting():
                yield settle
    finally:
        core.matcher.forget(pending)
        core.release_command_slot()
    if pending.reply is None:
        log.warning("%r: no reply after %d attempt(s)", text, pending.sent)
    elif not is_ok(pending.reply) and not text.endswith("?"):
        log.warning("%r -> %r", text, pending.reply)
    return pending.reply


def result_of(reply: str | None, what: str) -> tuple[int, str]:
    """(result, message) of a reply: 0 accepted, 2 refused with the Tello's text, -1 none."""
    if reply is None:
        return RESULT_NO_REPLY, f"{what}: no reply from the Tello"
    if is_ok(reply):
        return MAV_RESULT_ACCEPTED, f"{what} accepted"
    return MAV_RESULT_DENIED, f"{what} refused by the Tello: {reply}"


def connect(core: OperationPort) -> Steps:
    """``command`` until ``ok`` (SDK mode; the bridge's own). The video follows on the next
    tick (video_demand.py)."""
    reply = yield from exchange(core, "command", attempts=1)
    if reply is None or not is_ok(reply):
        return False
    core.in_sdk_mode()
    core.publish_state(force=True)
    return True


def switch_video(core: OperationPort, command: str) -> Steps:
    """``streamon`` or ``streamoff``, tried once (video_demand.py spaces and bounds the tries,
    so the command slot is free for flight commands in between). Before a ``streamon`` the
    video receiver is told to start afresh, so the new stream's first datagram finds it empty."""
    if command == STREAMON:
        core.restart_video()
    reply = yield from exchange(core, command, attempts=1)
    core.video_answered(command, reply)
    return reply


def arming(core: OperationPort, request: CommandBool) -> Steps:
    """A Tello has no arming. arm: enter SDK mode (``command``); the motors start with
    take-off. disarm: accepted on the ground (motors are off), refused in flight."""
    core.require_connected()
    if not request.value:
        if core.telemetry.landed.flying:
            return CommandBoolResult(
                success=False,
                result=MAV_RESULT_DENIED,
                message="a flying Tello cannot disarm: land (or set_mode EMERGENCY)",
            )
        return CommandBoolResult(
            success=True, result=0, message="a Tello has no arming: motors are off"
        )
    reply = yield from exchange(core, "command")
    result, message = result_of(reply, "command (SDK mode)")
    if result == 0:
        core.in_sdk_mode()
        message = "a Tello has no arming: SDK mode confirmed, the motors start with take-off"
    return CommandBoolResult(success=result == 0, result=result, message=message)


def takeoff(core: OperationPort, request: CommandTOL) -> Steps:
    """``takeoff`` (waits for the Tello's ok, which comes once it hovers, ~1 m), then
    ``up``/``down`` to ``altitude`` m above the take-off point when one is given. While
    flying it does nothing (a second take-off must not move the drone)."""
    core.require_connected()
    height = request.altitude
    if not math.isnan(height) and not (math.isfinite(height) and 0.0 < height <= 30.0):
        raise ValueError(f"altitude must be in (0, 30] m or NaN, got {height!r}")
    if core.telemetry.landed.state == LANDED_STATE_IN_AIR:
        return CommandTOLResult(success=True, result=0, message="already flying")
    try:  # above the envelope: refused, the limit named
        check_takeoff(core.missions.envelope, height)
    except EnvelopeError as exc:
        raise ServiceError(str(exc), "refused") from None
    core.telemetry.reset_position()
    core.telemetry.landed.on_takeoff_sent()
    core.failsafe.on_takeoff_or_land()
    core.publish_state(force=True)
    reply = yield from exchange(core, "takeoff", timeout=core.config.takeoff_timeout, attempts=1)
    result, message = result_of(reply, "takeoff")
    if reply is None and (core.telemetry.position_enu or (0, 0, 0))[2] > 0.3:
        result, message = 0, "takeoff: reply lost, but the Tello is in the air"
    core.telemetry.landed.on_takeoff_done(result == 0)
    core.publish_state(force=True)
    if result != 0 or math.isnan(height):
        return CommandTOLResult(success=result == 0, result=result, message=message)
    move_result, move_message, _ = yield from move_to_height(core, height)
    message += f"; {move_message}"
    return CommandTOLResult(success=move_result == 0, result=move_result, message=message)


def move_to_height(
    core: OperationPort, height: float
) -> Generator[float, None, tuple[int, str, str]]:
    """After the Tello's own take-off (which ends near 1 m), ``up``/``down`` to ``height`` m
    above the take-off point: (result, what was done, the move sent or ""). The SDK's moves
    are 20-500 cm, so an error of 8 cm or less is left (a 20 cm move would overshoot by more
    than it corrects)."""
    z = yield from settled_height(core)
    error_cm = (height - z) * 100.0
    if abs(error_cm) <= 8.0:
        return MAV_RESULT_ACCEPTED, f"the Tello's take-off ended at {z:.2f} m, as asked", ""
    verb = "up" if error_cm > 0 else "down"
    move = f"{verb} {round(min(500.0, max(20.0, abs(error_cm))))}"
    log.info("the Tello's own take-off ended at %.2f m; %s to the %.2f m asked", z, move, height)
    reply = yield from exchange(core, move, timeout=core.config.move_timeout, attempts=1)
    result, message = result_of(reply, move)
    if result != MAV_RESULT_ACCEPTED:
        return result, f"the Tello's take-off ended at {z:.2f} m; {message}", move
    done = f"the Tello's take-off ended at {z:.2f} m, then {move} to the {height:g} m asked"
    return result, done, move


def settled_height(core: OperationPort, timeout: float = 3.0) -> Generator[float, None, float]:
    """The height (m) once the climb has stopped: the take-off ``ok`` may come while the
    Tello still rises the last centimetres. Settled = two state strings in a row with
    |vz| < 0.1 m/s; gives up after ``timeout`` s."""
    deadline = core.now + timeout
    calm, seen = 0, core.states_received
    while core.now < deadline and calm < 2:
        yield deadline
        if core.states_received != seen:
            seen = core.states_received
            calm = calm + 1 if abs(core.telemetry.velocity[2]) < 0.1 else 0
    return (core.telemetry.position_enu or (0.0, 0.0, 0.0))[2]


def landing(core: OperationPort) -> Generator[float, None, str | None]:
    """``land``, once, waiting for the Tello's ok (given on the ground); the reply or None."""
    core.telemetry.landed.on_land_sent()
    core.failsafe.on_takeoff_or_land()
    core.publish_state(force=True)
    reply = yield from exchange(core, "land", timeout=core.config.land_timeout, attempts=1)
    core.telemetry.landed.on_land_done(reply is not None and is_ok(reply))
    core.publish_state(force=True)
    return reply


def land(core: OperationPort, request: CommandTOL) -> Steps:
    """``land`` here (waits for the Tello's ok, given once on the ground)."""
    core.require_connected()
    for name, value, bound in (
        ("latitude", request.latitude, 90.0),
        ("longitude", request.longitude, 180.0),
    ):
        if not math.isnan(value) and not (math.isfinite(value) and abs(value) <= bound):
            raise ValueError(f"{name} must be within ±{bound:g} degrees or NaN, got {value!r}")
    if core.telemetry.landed.state == LANDED_STATE_ON_GROUND:
        return CommandTOLResult(success=True, result=0, message="already on the ground")
    result, message = result_of((yield from landing(core)), "land")
    return CommandTOLResult(success=result == 0, result=result, message=message)


def failsafe_land(core: OperationPort) -> Steps:
    """The failsafe's landing (commander lost); nobody waits for it."""
    reply = yield from landing(core)
    if reply is not None and is_ok(reply):
        log.warning("failsafe land: done")
    else:
        log.error("failsafe land: %s", reply or "no reply")
    return reply


# ---------------------------------------------------------------- modes and parameters


def hover(core: OperationPort) -> Steps:
    """``stop``: hover where it is (a cancelled take-off or landing); the reply's text."""
    core.failsafe.on_takeoff_or_land()
    reply = yield from exchange(core, "stop")
    return result_of(reply, "stop")[1]


def set_mode(core: OperationPort, request: SetMode) -> Steps:
    """Modes mapped onto Tello commands: OFFBOARD/GUIDED/SDK -> ``command``;
    AUTO.LOITER/HOLD/LOITER/POSCTL/BRAKE -> ``stop`` (hover); AUTO.LAND/LAND -> ``land``;
    EMERGENCY -> ``emergency`` (motors off at once: it falls)."""
    core.require_connected()
    mode = request.custom_mode.strip().upper() if isinstance(request.custom_mode, str) else ""
    if mode not in ALL_MODES:
        raise ValueError(
            f"custom_mode {request.custom_mode[:40]!r} is not a Tello mode; "
            f"valid: {', '.join(ALL_MODES)}"
        )
    if mode in SDK_MODES:
        reply = yield from exchange(core, "command")
        if reply is not None and is_ok(reply):
            core.in_sdk_mode()
    elif mode in HOVER_MODES:
        core.failsafe.on_takeoff_or_land()
        reply = yield from exchange(core, "stop")
    elif mode in LAND_MODES:
        if core.telemetry.landed.state == LANDED_STATE_ON_GROUND:
            return SetModeResult(mode_sent=True, result=0, message="already on the ground")
        reply = yield from landing(core)
    else:
        reply = yield from exchange(core, "emergency", attempts=1)
        core.telemetry.landed.on_emergency()
    result, message = result_of(
        reply, f"{mode} ({'emergency' if mode in EMERGENCY_MODES else 'mapped'})"
    )
    return SetModeResult(mode_sent=result == 0, result=result, message=message)


def param_id_of(param_id: Any) -> str:
    """The known parameter id (upper case); ValueError listing the known ones."""
    if not isinstance(param_id, str) or param_id.upper() not in PARAMS:
        shown = param_id[:40] if isinstance(param_id, str) else param_id
        raise ValueError(f"param_id {shown!r} is not a Tello parameter; known: {', '.join(PARAMS)}")
    return param_id.upper()


def number_in(text: str) -> float | None:
    """The first number in a reply (``100.0``, ``87``, ``-3``), None if there is none."""
    match = _NUMBER.search(text)
    return float(match.group()) if match else None


def param_get(core: OperationPort, request: ParamGet) -> Steps:
    """Read commands (``speed?``, ``battery?`` ...) as parameters (numbers only)."""
    core.require_connected()
    param_id = param_id_of(request.param_id)
    reply = yield from exchange(core, PARAMS[param_id][0])
    if reply is None:
        return ParamGetResult(success=False, message=f"{param_id}: no reply from the Tello")
    value = number_in(reply)
    if value is None:
        return ParamGetResult(success=False, message=f"{param_id}: the Tello said {reply!r}")
    return ParamGetResult(success=True, value=ParamValue.of(value), message=reply)


def param_set(core: OperationPort, request: ParamSet) -> Steps:
    """Only SPEED (cm/s, ``speed x``, 10..100) can be written."""
    core.require_connected()
    param_id = param_id_of(request.param_id)
    setter = PARAMS[param_id][1]
    if setter is None:
        return ParamSetResult(success=False, message=f"{param_id} is read-only on a Tello")
    value = float(request.value.as_number())
    verb, low, high = setter
    if not (math.isfinite(value) and low <= value <= high):
        raise ValueError(
            f"value: {param_id} (real or integer) must be in [{low:g}, {high:g}], got {value!r}"
        )
    command = f"{verb} {round(value)}"
    reply = yield from exchange(core, command)
    result, message = result_of(reply, command)
    return ParamSetResult(
        success=result == 0, value=ParamValue.of(float(round(value))), message=message
    )
