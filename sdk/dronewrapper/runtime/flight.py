"""Take-off and landing as steps a service's loop drives (never blocking), on a Commander.

The same sequences as the SDK's blocking ``DroneWrapper.takeoff`` / ``land`` (docs/design.md),
written as generators that yield while they wait, so a loop calls ``step(now)`` once per wake
and keeps watching its inputs (and its stop request) meanwhile:

- take-off, PX4 and the PX4-like simulator: stream a hold setpoint at the current pose, enter
  OFFBOARD, arm, stream a position setpoint ``height`` m above the start, wait for the climb;
  ArduPilot: GUIDED, arm, TAKEOFF; Tello: TAKEOFF. Already flying: done at once (a warning).
  The climb fails when the autopilot disarms or leaves the mode it was put in.
- landing: stop streaming, call LAND (unless on the ground and disarmed), wait until on the
  ground and disarmed.

A step that is refused, a call without a reply, or a deadline passed ends the sequence with a
:class:`FlightError` naming what failed. Time: the loop's monotonic clock (s); heights in
metres in the local ENU frame (z up, origin at the take-off point).
"""

from __future__ import annotations

import logging
import math
from collections.abc import Generator
from typing import Any

from dronewrapper import setpoints, telemetry
from dronewrapper.drone import ARDUPILOT, TELLO
from dronewrapper.msgs import registry
from dronewrapper.msgs.mavros import (
    LANDED_STATE_IN_AIR,
    LANDED_STATE_ON_GROUND,
    LANDED_STATE_TAKEOFF,
    CommandBool,
    CommandTOL,
    SetMode,
)
from dronewrapper.msgs.registry import Service
from dronewrapper.runtime.commander import Commander
from dronewrapper.runtime.errors import ServiceError, ServiceUnavailable

log = logging.getLogger("dronewrapper.flight")

Steps = Generator[None, None, None]

CALL_TIMEOUT_S = 10.0
"""The longest wait for one reply (s), as the SDK's ``service_timeout`` default."""


class FlightError(RuntimeError):
    """A take-off or landing failed; the message names the step and the autopilot's reason."""


class FlightSequence:
    """A generator of steps with an overall deadline; :meth:`step` advances it.

    ``done`` is True once it finished; ``error`` holds the :class:`FlightError` if it failed
    (``step`` raises it once, then keeps returning True).
    """

    what = "sequence"

    def __init__(self, commander: Commander, timeout: float, now: float) -> None:
        if not (math.isfinite(timeout) and timeout > 0):
            raise ValueError(f"{self.what} timeout must be > 0 s, got {timeout!r}")
        self.commander = commander
        self.timeout = timeout
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
        timeout = min(CALL_TIMEOUT_S, self._remaining())
        pending = self.commander.call(service, request, self.now, timeout=timeout)
        while not pending.done(self.now):
            yield
        try:
            reply = pending.result(self.now)
        except (ServiceUnavailable, TimeoutError) as exc:  # no answer (before ServiceError,
            raise FlightError(f"{what}: {exc}") from None  # of which it is a kind)
        except ServiceError as exc:
            raise FlightError(f"{what} refused: {exc.message}") from None
        accepted = reply.mode_sent if hasattr(reply, "mode_sent") else reply.success
        if not accepted:
            raise FlightError(f"{what} refused: {reply.message or 'no reason given'}")


class Takeoff(FlightSequence):
    """Take off to ``height`` m above the start point within ``timeout`` s (see module doc)."""

    what = "takeoff"

    def __init__(
        self,
        commander: Commander,
        height: float,
        timeout: float,
        now: float,
        *,
        tolerance: float = 0.1,
    ) -> None:
        height = setpoints.finite("height", height)
        if height <= 0:
            raise ValueError(f"height must be > 0 m, got {height}")
        self.height = height
        self.tolerance = tolerance
        self.target_z = math.nan
        super().__init__(commander, timeout, now)

    def _run(self) -> Steps:
        c = self.commander
        state = c.connected_state()
        if state is None:
            raise FlightError(f"takeoff: {c.not_ready_reason()}")
        extended, start = c.extended.value, c.pose.value
        if extended is not None and extended.landed_state in (
            LANDED_STATE_IN_AIR,
            LANDED_STATE_TAKEOFF,
        ):
            log.warning("takeoff: drone %r is already flying, so this does nothing", c.ns)
            return
        if start is None:
            raise FlightError(f"takeoff: no local position on {c.pose.name}")
        x, y, z0 = (float(v) for v in telemetry.position_of(start))
        yaw = float(telemetry.orientation_of(start)[2])
        on_ground = extended is None or extended.landed_state == LANDED_STATE_ON_GROUND
        # h above the point it takes off from; caught mid-landing, h above the origin
        self.target_z = (z0 if on_ground else 0.0) + self.height
        autopilot = state.autopilot.lower()
        log.info("takeoff: drone %r to %.2f m (%s)", c.ns, self.target_z, autopilot or "?")
        stamp = c.wall()
        if autopilot in ARDUPILOT:
            yield from self._command(registry.SET_MODE, SetMode(custom_mode="GUIDED"), "GUIDED")
            yield from self._command(registry.ARMING, CommandBool(value=True), "arming")
            takeoff = CommandTOL.takeoff(self.height, yaw)
            yield from self._command(registry.TAKEOFF, takeoff, "takeoff")
            mode = "GUIDED"
        elif autopilot in TELLO:
            yield from self._command(registry.TAKEOFF, CommandTOL.takeoff(self.height), "takeoff")
            mode = ""
        else:  # PX4 and the PX4-like simulator: OFFBOARD with a setpoint stream
            c.set(setpoints.position_target(x, y, z0, yaw, stamp=stamp), self.now)
            try:
                yield from self._command(
                    registry.SET_MODE, SetMode(custom_mode="OFFBOARD"), "set_mode OFFBOARD"
                )
                yield from self._command(registry.ARMING, CommandBool(value=True), "arming")
            except FlightError:
                c.stop()
                raise
            c.set(setpoints.position_target(x, y, self.target_z, yaw, stamp=stamp), self.now)
            mode = "OFFBOARD"
        log.info("takeoff: armed, climbing")
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
                    raise FlightError("takeoff: the autopilot disarmed during the climb")
                if seen_mode and mode and state.mode != mode:
                    raise FlightError(f"takeoff: the autopilot left {mode} for {state.mode}")
            pose = c.pose.value
            if pose is not None and pose.pose.position.z >= self.target_z - self.tolerance:
                return
            if self.now >= self.deadline:
                z = f"{pose.pose.position.z:.2f} m" if pose is not None else "unknown"
                raise FlightError(
                    f"takeoff: altitude {self.target_z:.2f} m not reached within "
                    f"{self.timeout:g} s (now {z})"
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
        log.info("land: drone %r landing", c.ns)
        while not self._landed():
            if self.now >= self.deadline:
                raise FlightError(f"land: not on the ground and disarmed within {self.timeout:g} s")
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
