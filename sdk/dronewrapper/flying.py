"""The SDK's blocking take-off and landing: the runtime's flight steps, driven to the end.

``DroneWrapper.takeoff`` / ``land`` build the :mod:`dronewrapper.runtime.flight` ``Takeoff`` /
``Landing`` that a service's loop steps, on a :class:`WrapperAircraft` (the wrapper's telemetry,
setpoint stream and service calls), and :func:`fly` steps them on the caller's thread until
done. A service call blocks its step (up to the wrapper's ``service_timeout``); the climb and
the descent are watched every ``interval`` s of the wrapper's clock. A :class:`FlightError`
becomes the SDK's exception (:func:`drone_error`), with the same text.
"""

from __future__ import annotations

import collections
from collections.abc import Callable
from concurrent.futures import Future
from typing import Any

from dronewrapper.errors import Cancelled, CommandRefused, DroneError, NoData, NotConnected, Timeout
from dronewrapper.msgs.mavros import ExtendedState, PositionTarget, State, StatusText
from dronewrapper.msgs.registry import Service
from dronewrapper.runtime.commander import STATE_FRESH_S, Pending
from dronewrapper.runtime.flight import (
    FlightError,
    FlightSequence,
    NoPosition,
    NoReply,
    StepRefused,
    TooLate,
)
from dronewrapper.runtime.latest import Latest

POLL_INTERVAL_S = 0.02
"""How often a blocking take-off or landing looks at the telemetry (s)."""


class WrapperAircraft:
    """A DroneWrapper's side of :class:`~dronewrapper.runtime.flight.Aircraft`.

    Args:
        ns: the vehicle namespace.
        state, extended, pose: the wrapper's newest-value holders.
        status_texts: the wrapper's autopilot texts (newest last).
        set_target: streams a setpoint (the wrapper's setpoint stream).
        stop: stops the stream.
        ask: ``ask(service, request, timeout)``: a blocking call that returns the reply or
            raises the runtime's ServiceError / ServiceUnavailable.
        wall: Unix time (s), the stamp of the take-off setpoints.
    """

    def __init__(
        self,
        ns: str,
        *,
        state: Latest[State],
        extended: Latest[ExtendedState],
        pose: Latest[Any],
        status_texts: collections.deque[StatusText],
        set_target: Callable[[PositionTarget], None],
        stop: Callable[[], None],
        ask: Callable[[Service[Any, Any], Any, float], Any],
        wall: Callable[[], float],
    ) -> None:
        self.ns = ns
        self.state, self.extended, self.pose = state, extended, pose
        self.wall = wall
        self._texts = status_texts
        self._set_target, self._stop, self._ask = set_target, stop, ask

    def connected_state(self) -> State | None:
        state = self.state.fresh(STATE_FRESH_S)
        return state if state is not None and state.connected else None

    def not_ready_reason(self) -> str:
        return "the bridge's autopilot is not connected"

    def last_status_text(self) -> str:
        return self._texts[-1].text if self._texts else ""

    def set(self, target: PositionTarget, now: float) -> None:
        self._set_target(target)

    def stop(self) -> None:
        self._stop()

    def call(
        self, service: Service[Any, Any], request: Any, now: float, *, timeout: float, what: str
    ) -> Pending[Any]:
        """Ask now, on this thread; the Pending is answered when returned."""
        future: Future[Any] = Future()
        try:
            future.set_result(self._ask(service, request, timeout))
        except Exception as exc:
            future.set_exception(exc)
        return Pending(what, future, now + timeout, timeout)


def drone_error(exc: FlightError, no_reply: Callable[[str, str, float], DroneError]) -> DroneError:
    """The SDK's exception for a failed step; ``no_reply(what, key, timeout)`` tells a missing
    bridge (NotConnected) from a silent one (Timeout)."""
    if isinstance(exc, StepRefused):
        return CommandRefused(exc.command, exc.reason, exc.result)
    if isinstance(exc, NoReply):
        return no_reply(exc.command, exc.key, exc.timeout)
    if isinstance(exc, TooLate):
        return Timeout(str(exc))
    if isinstance(exc, NoPosition):
        return NoData(str(exc))
    return NotConnected(str(exc))


def fly(
    sequence: FlightSequence,
    *,
    clock: Callable[[], float],
    sleep: Callable[[float], Any],
    no_reply: Callable[[str, str, float], DroneError],
    interval: float = POLL_INTERVAL_S,
    cancelled: Callable[[], bool] = lambda: False,
) -> None:
    """Step ``sequence`` until it is done, sleeping ``interval`` s between steps.

    Raises:
        DroneError: the sequence failed (see :func:`drone_error`).
        Cancelled: ``cancelled()`` became true: no further step was taken.
    """
    try:
        while not sequence.step(clock()):
            sleep(interval)
            if cancelled():
                raise Cancelled(f"{type(sequence).__name__.lower()} cancelled")
    except FlightError as exc:
        raise drone_error(exc, no_reply) from None
