"""The bridge's long actions as steps a loop drives (never blocking): one request each.

Take-off, landing, go-to, return and a mission's start, pause and resume. The bridge flies
each its aircraft's way and answers once it has ended (``{ns}/dronewrapper/takeoff``,
``land``, ``goto``, ``return``, ``mission``, :mod:`dronewrapper.msgs.flight`), so nothing here
depends on the aircraft: no mode names, no status texts read. Written once, as generators that
yield while they wait, on a :class:`~dronewrapper.client.DroneClient`, driven two ways: a
service's loop (the controller) calls ``step(now)`` once per wake and keeps watching its inputs
and its stop request meanwhile; the SDK's blocking ``DroneWrapper.takeoff``, ``land``, ... call
``step`` until done (:mod:`dronewrapper.flights`). A landing stops the caller's setpoint stream
first.

A failure ends the sequence with a :class:`FlightError` of one kind: :class:`StepRefused`
(the autopilot's or the bridge's reason), :class:`NoReply` (the request nobody answered),
:class:`TooLate` (the deadline passed; the message names the altitude, mode and arming),
:class:`NotReady` (no connected aircraft) or :class:`NoPosition` (nothing to start from).
Time: the driver's monotonic clock (s); heights in metres above the take-off point.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Generator
from typing import Any, Protocol

from dronewrapper import setpoints
from dronewrapper.msgs import registry
from dronewrapper.msgs.flight import (
    NO_HOME,
    NO_POSITION,
    REFUSED,
    TOO_LATE,
    FlightResult,
    GotoRequest,
    LandRequest,
    MissionRequest,
    ReturnRequest,
    TakeoffRequest,
)
from dronewrapper.msgs.mavros import State
from dronewrapper.msgs.registry import Service
from dronewrapper.runtime.errors import ServiceError, ServiceUnavailable

log = logging.getLogger("dronewrapper.flight")

# a flight's steps: a generator the caller steps on each new input until it returns the result
FlightSteps = Generator[None, None, Any]

CALL_TIMEOUT_S = 10.0
"""How long a reply may take beyond the manoeuvre's own timeout (s), as the SDK's
``service_timeout`` default."""


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
    """Nothing to start from: no connected aircraft."""


class NoPosition(NotReady):
    """No local position has arrived, so there is no point to take off from."""


class Aircraft(Protocol):
    """What the sequences need: a :class:`~dronewrapper.client.DroneClient`, stepped by a
    service's loop or by the SDK's blocking calls."""

    ns: str

    def connected_state(self) -> State | None: ...
    def not_ready_reason(self) -> str: ...
    def stop(self) -> None: ...
    def call(
        self, service: Service[Any, Any], request: Any, now: float, *, timeout: float, what: str
    ) -> Any: ...  # a Pending: ``done(now)``, ``result(now)``


def failure(what: str, reply: FlightResult) -> FlightError:
    """The error a failed :class:`~dronewrapper.msgs.flight.FlightResult` stands for."""
    if reply.failure == REFUSED:
        return StepRefused(reply.step or what, reply.message, reply.result)
    if reply.failure == TOO_LATE:
        return TooLate(f"{what}: {reply.message}")
    if reply.failure in (NO_POSITION, NO_HOME):
        return NoPosition(f"{what}: {reply.message}")
    return NotReady(f"{what}: {reply.message or 'the bridge gave no reason'}")


class FlightSequence:
    """One request and the wait for its reply; :meth:`step` advances it.

    ``done`` is True once it finished; ``error`` holds the :class:`FlightError` if it failed
    (``step`` raises it once, then keeps returning True); ``result`` the bridge's reply. The
    reply is awaited ``timeout`` s plus ``call_timeout`` (None: :data:`CALL_TIMEOUT_S`).
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
        self.now = now
        self.done = False
        self.error: FlightError | None = None
        self.result: FlightResult | None = None
        self._steps = self._run()

    def _run(self) -> FlightSteps:
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

    def _request(self, service: Service[Any, FlightResult], request: Any) -> FlightSteps:
        """Ask the bridge and wait (yielding) for its reply; raises the failure it reports."""
        c = self.commander
        if c.connected_state() is None:
            raise NotReady(f"{self.what}: {c.not_ready_reason()}")
        timeout = self.timeout + (self.call_timeout or CALL_TIMEOUT_S)
        pending = c.call(service, request, self.now, timeout=timeout, what=self.what)
        while not pending.done(self.now):
            yield
        try:
            reply = pending.result(self.now)
        except (ServiceUnavailable, TimeoutError) as exc:  # no answer (before ServiceError,
            waited = getattr(exc, "waited", None)  # its kind); the time actually waited
            waited = timeout if waited is None else waited
            raise NoReply(self.what, service.key(c.ns), waited, str(exc)) from None
        except ServiceError as exc:
            raise StepRefused(self.what, exc.message) from None
        self.result = reply
        if not reply.success:
            raise failure(self.what, reply)
        if math.isnan(reply.height) and self.what == "takeoff":
            log.warning("takeoff: drone %r: %s", c.ns, reply.message)  # nothing was done
        else:
            log.info("%s: drone %r: %s", self.what, c.ns, reply.message)
        return reply


class Takeoff(FlightSequence):
    """Take off to ``height`` m above the take-off point within ``timeout`` s, done within
    ``tolerance`` m of it. Already flying: done at once, with a warning that says so."""

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
        super().__init__(aircraft, timeout, now, call_timeout=call_timeout)

    def _run(self) -> FlightSteps:
        log.info("takeoff: drone %r to %.2f m", self.commander.ns, self.height)
        request = TakeoffRequest(
            height=self.height, timeout=self.timeout, tolerance=min(self.tolerance, self.height / 2)
        )
        yield from self._request(registry.FLIGHT_TAKEOFF, request)


class Landing(FlightSequence):
    """Land where the drone is and wait until on the ground and disarmed (``timeout`` s)."""

    what = "land"

    def _run(self) -> FlightSteps:
        self.commander.stop()
        yield from self._request(registry.FLIGHT_LAND, LandRequest(timeout=self.timeout))


class Goto(FlightSequence):
    """Fly to a point (``request``: ENU m from home, or latitude/longitude) and hold there; done
    within the request's tolerance, within its timeout."""

    what = "goto"

    def __init__(
        self,
        aircraft: Aircraft,
        request: GotoRequest,
        now: float,
        *,
        call_timeout: float | None = None,
    ) -> None:
        self.request = request
        super().__init__(aircraft, request.timeout, now, call_timeout=call_timeout)

    def _run(self) -> FlightSteps:
        self.commander.stop()  # the bridge holds the point: no setpoint of ours may override it
        yield from self._request(registry.FLIGHT_GOTO, self.request)


class Return(FlightSequence):
    """Fly home and land; done once on the ground and disarmed (``timeout`` s)."""

    what = "return"

    def __init__(
        self,
        aircraft: Aircraft,
        timeout: float,
        now: float,
        *,
        watch: str = "",
        call_timeout: float | None = None,
    ) -> None:
        self.watch = watch
        super().__init__(aircraft, timeout, now, call_timeout=call_timeout)

    def _run(self) -> FlightSteps:
        self.commander.stop()
        yield from self._request(
            registry.FLIGHT_RETURN, ReturnRequest(timeout=self.timeout, watch=self.watch)
        )


class MissionStep(FlightSequence):
    """Start, pause or resume the uploaded mission; done once the aircraft flies it (or
    holds)."""

    def __init__(
        self,
        aircraft: Aircraft,
        action: str,
        timeout: float,
        now: float,
        *,
        watch: str = "",
        call_timeout: float | None = None,
    ) -> None:
        self.request = MissionRequest(action=action, timeout=timeout, watch=watch)
        self.what = f"{action}_mission"
        super().__init__(aircraft, timeout, now, call_timeout=call_timeout)

    def _run(self) -> FlightSteps:
        if self.request.action != "pause":
            self.commander.stop()
        yield from self._request(registry.FLIGHT_MISSION, self.request)
