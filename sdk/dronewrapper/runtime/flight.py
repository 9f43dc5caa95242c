"""Take-off and landing as steps a loop drives (never blocking): the one implementation.

Written once, as generators that yield while they wait, and driven two ways: a service's loop
(the controller, on a :class:`~dronewrapper.runtime.commander.Commander`) calls ``step(now)``
once per wake and keeps watching its inputs and its stop request meanwhile; the SDK's blocking
``DroneWrapper.takeoff`` / ``land`` call ``step`` until done (:mod:`dronewrapper.flying`).
The sequences (docs/design.md):

- take-off, PX4 and the PX4-like simulator: stream a hold setpoint at the current pose, enter
  OFFBOARD, arm, stream a position setpoint ``height`` m above the start, wait for the climb;
  ArduPilot: GUIDED, arm, TAKEOFF; Tello: TAKEOFF. Already flying: done at once, with a
  warning that says so. The climb fails when the autopilot disarms or leaves the mode it was
  put in.
- landing: stop streaming, call LAND (unless on the ground and disarmed), wait until on the
  ground and disarmed.

A failure ends the sequence with a :class:`FlightError` of one kind: :class:`StepRefused`
(the autopilot's or the bridge's reason), :class:`NoReply` (a call nobody answered),
:class:`TooLate` (the deadline passed; the message names the altitude, mode and arming),
:class:`NotReady` (no connected autopilot) or :class:`NoPosition` (nothing to start from).
Time: the driver's monotonic clock (s); heights in metres in the local ENU frame (z up,
origin at the take-off point).
"""

from __future__ import annotations

import logging
import math
from collections.abc import Generator
from typing import Any, Protocol

from dronewrapper import setpoints, telemetry
from dronewrapper.msgs import registry
from dronewrapper.msgs.mavros import (
    LANDED_STATE_IN_AIR,
    LANDED_STATE_ON_GROUND,
    LANDED_STATE_TAKEOFF,
    CommandBool,
    CommandTOL,
    PositionTarget,
    SetMode,
    State,
)
from dronewrapper.msgs.registry import Service
from dronewrapper.runtime.errors import ServiceError, ServiceUnavailable

log = logging.getLogger("dronewrapper.flight")

Steps = Generator[None, None, None]

ARDUPILOT = ("ardupilotmega", "ardupilot")
TELLO = ("tello",)
"""``State.autopilot`` names that take off by command (the rest: PX4-like, by setpoints)."""

CALL_TIMEOUT_S = 10.0
"""The longest wait for one reply (s), as the SDK's ``service_timeout`` default."""


class FlightError(RuntimeError):
    """A take-off or landing failed; the message names the step and the autopilot's reason."""


class StepRefused(FlightError):
    """A step was refused (or the autopilot gave up the climb): ``command``, ``reason`` and
    ``result`` (the MAV_RESULT code; None when the bridge itself rejected the request)."""

    def __init__(self, command: str, reason: str, result: int | None = None) -> None:
        code = "" if result is None else f" (result {result})"
        super().__init__(f"{command} refused{code}: {reason or 'no reason given'}")
        self.command = command
        self.reason = reason
        self.result = result


class NoReply(FlightError):
    """Nobody answered ``command`` on ``key`` within ``timeout`` s."""

    def __init__(self, command: str, key: str, timeout: float, detail: str) -> None:
        super().__init__(f"{command}: {detail}")
        self.command = command
        self.key = key
        self.timeout = timeout


class TooLate(FlightError):
    """The sequence's deadline passed before the altitude or the ground was reached."""


class NotReady(FlightError):
    """Nothing to start from: no connected autopilot."""


class NoPosition(NotReady):
    """No local position has arrived, so there is no point to take off from."""


class Aircraft(Protocol):
    """What the sequences read and command: :class:`~dronewrapper.runtime.commander.Commander`
    on a service's loop, ``dronewrapper.flying.WrapperAircraft`` in the SDK."""

    ns: str
    state: Any  # Latest[State]: ``.value``
    extended: Any  # Latest[ExtendedState]
    pose: Any  # Latest[PoseStamped]: ``.value``, ``.name``

    def wall(self) -> float: ...
    def connected_state(self) -> State | None: ...
    def not_ready_reason(self) -> str: ...
    def last_status_text(self) -> str: ...
    def set(self, target: PositionTarget, now: float) -> None: ...
    def stop(self) -> None: ...
    def call(
        self, service: Service[Any, Any], request: Any, now: float, *, timeout: float, what: str
    ) -> Any: ...  # a Pending: ``done(now)``, ``result(now)``


class FlightSequence:
    """A generator of steps with an overall deadline; :meth:`step` advances it.

    ``done`` is True once it finished; ``error`` holds the :class:`FlightError` if it failed
    (``step`` raises it once, then keeps returning True). ``call_timeout`` (s) bounds each
    service call; None: :data:`CALL_TIMEOUT_S`, capped by what is left of the deadline.
    """

    what = "sequence"

    def __init__(
        self,
        aircraft: Aircraft,
        timeout: float,
        now: float,
        *,
        call_timeout: float | None = None,
    ) -> None:
        if not (math.isfinite(timeout) and timeout > 0):
            raise ValueError(f"{self.what} timeout must be > 0 s, got {timeout!r}")
        self.commander = aircraft
        self.timeout = timeout
        self.call_timeout = call_timeout
        self.deadline = now + timeout
        self.now = now
        self.done = False
        self.error: FlightError | None = None
        self._steps = self._run()

    def _run(self) -> Steps:
        raise NotImplementedError

    def step(self, now: float) -> bool:
        """Advance as far as possible without waiting; True once finished (either way).

        Raises:
            FlightError: the sequence failed just now.
        """
        if self.done:
            return True
        self.now = now
        try:
            next(self._steps)
        except StopIteration:
            self.done = True
        except FlightError as exc:
            self.done, self.error = True, exc
            raise
        return self.done

    def _remaining(self) -> float:
        return max(0.001, self.deadline - self.now)

    def _command(self, service: Service[Any, Any], request: Any, what: str) -> Steps:
        """Call ``service`` and wait (yielding) for an accepting reply."""
        c = self.commander
        timeout = self.call_timeout or min(CALL_TIMEOUT_S, self._remaining())
        pending = c.call(service, request, self.now, timeout=timeout, what=what)
        while not pending.done(self.now):
            yield
        try:
            reply = pending.result(self.now)
        except (ServiceUnavailable, TimeoutError) as exc:  # no answer (before ServiceError,
            raise NoReply(what, service.key(c.ns), timeout, str(exc)) from None  # its kind)
        except ServiceError as exc:
            raise StepRefused(what, exc.message) from None
        accepted = reply.mode_sent if hasattr(reply, "mode_sent") else reply.success
        if not accepted:
            raise StepRefused(what, reply.message, getattr(reply, "result", None))

    def _altitude_text(self) -> str:
        pose = self.commander.pose.value
        return "no position" if pose is None else f"z={pose.pose.position.z:.2f} m"

    def _last_text(self) -> str:
        text = self.commander.last_status_text()
        return f" ({text})" if text else ""


class Takeoff(FlightSequence):
    """Take off to ``height`` m above the start point within ``timeout`` s (see module doc)."""

    what = "takeoff"

    def __init__(
        self,
        aircraft: Aircraft,
        height: float,
        timeout: float,
        now: float,
        *,
        tolerance: float = 0.1,
        call_timeout: float | None = None,
    ) -> None:
        height = setpoints.finite("height", height)
        if height <= 0:
            raise ValueError(f"height must be > 0 m, got {height}")
        self.height = height
        self.tolerance = tolerance
        self.target_z = math.nan
        super().__init__(aircraft, timeout, now, call_timeout=call_timeout)

    def _run(self) -> Steps:
        c = self.commander
        state = c.connected_state()
        if state is None:
            raise NotReady(f"takeoff: {c.not_ready_reason()}")
        extended, start = c.extended.value, c.pose.value
        if extended is not None and extended.landed_state in (
            LANDED_STATE_IN_AIR,
            LANDED_STATE_TAKEOFF,
        ):
            log.warning(
                "takeoff(h=%g): drone %r is already flying (%s), so this does nothing; "
                "use set_cmd_pos(z=...) or set_cmd_mix(z=...) to change altitude",
                self.height,
                c.ns,
                self._altitude_text(),
            )
            return
        if start is None:
            raise NoPosition(f"takeoff: no local position on {c.pose.name}: cannot take off")
        x, y, z0 = (float(v) for v in telemetry.position_of(start))
        yaw = float(telemetry.orientation_of(start)[2])
        on_ground = extended is None or extended.landed_state == LANDED_STATE_ON_GROUND
        # h above the point it takes off from; caught mid-landing, h above the origin
        self.target_z = (z0 if on_ground else 0.0) + self.height
        autopilot = state.autopilot.lower()
        log.info("takeoff: drone %r to %.2f m (%s)", c.ns, self.target_z, autopilot or "?")
        stamp = c.wall()
        if autopilot in ARDUPILOT:
            yield from self._command(
                registry.SET_MODE, SetMode(custom_mode="GUIDED"), "set_mode GUIDED"
            )
            yield from self._command(registry.ARMING, CommandBool(value=True), "arming")
            log.info("takeoff: armed in GUIDED, climbing")
            takeoff = CommandTOL.takeoff(self.height, yaw)
            yield from self._command(registry.TAKEOFF, takeoff, "takeoff")
            mode = "GUIDED"
        elif autopilot in TELLO:
            yield from self._command(registry.TAKEOFF, CommandTOL.takeoff(self.height), "takeoff")
            log.info("takeoff: the Tello took off, climbing")
            mode = ""
        else:  # PX4 and the PX4-like simulator: OFFBOARD with a setpoint stream
            c.set(setpoints.position_target(x, y, z0, yaw, stamp=stamp), self.now)
            try:
                yield from self._command(
                    registry.SET_MODE, SetMode(custom_mode="OFFBOARD"), "set_mode OFFBOARD"
                )
                yield from self._command(registry.ARMING, CommandBool(value=True), "arming")
            except GeneratorExit:  # abandoned by its loop: whatever streams now is not ours
                raise
            except BaseException:  # refused, unanswered, or interrupted (Ctrl-C in the SDK)
                c.stop()
                raise
            log.info("takeoff: armed in OFFBOARD, climbing")
            c.set(setpoints.position_target(x, y, self.target_z, yaw, stamp=stamp), self.now)
            mode = "OFFBOARD"
        yield from self._climb(mode)
        log.info("takeoff: reached %.2f m", self.target_z)

    def _climb(self, mode: str) -> Steps:
        c = self.commander
        seen_armed = seen_mode = False
        while True:
            state = c.state.value
            if state is not None:
                seen_armed |= state.armed
                seen_mode |= not mode or state.mode == mode
                if seen_armed and not state.armed:
                    raise StepRefused("takeoff", f"the autopilot disarmed{self._last_text()}")
                if seen_mode and mode and state.mode != mode:
                    raise StepRefused(
                        "takeoff", f"the autopilot left {mode} for {state.mode}{self._last_text()}"
                    )
            pose = c.pose.value
            if pose is not None and pose.pose.position.z >= self.target_z - self.tolerance:
                return
            if self.now >= self.deadline:
                raise TooLate(
                    f"takeoff: altitude {self.target_z:.2f} m not reached within "
                    f"{self.timeout:g} s (now {self._altitude_text()}, mode "
                    f"{state.mode if state else '?'}, armed {state.armed if state else '?'})"
                )
            yield


class Landing(FlightSequence):
    """Land where the drone is and wait until on the ground and disarmed (``timeout`` s)."""

    what = "land"

    def _run(self) -> Steps:
        c = self.commander
        c.stop()
        if self._landed():
            return
        yield from self._command(registry.LAND, CommandTOL.land(), "land")
        log.info("land: drone %r landing from %s", c.ns, self._altitude_text())
        while not self._landed():
            if self.now >= self.deadline:
                ext, state = c.extended.value, c.state.value
                raise TooLate(
                    f"land: not on the ground and disarmed within {self.timeout:g} s (now "
                    f"{self._altitude_text()}, landed_state {ext.landed_state if ext else '?'}, "
                    f"armed {state.armed if state else '?'})"
                )
            yield
        log.info("land: drone %r on the ground and disarmed", c.ns)

    def _landed(self) -> bool:
        ext, state = self.commander.extended.value, self.commander.state.value
        return bool(
            ext is not None
            and ext.landed_state == LANDED_STATE_ON_GROUND
            and state is not None
            and not state.armed
        )
