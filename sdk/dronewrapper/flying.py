"""The SDK's blocking take-off and landing: the runtime's flight steps, driven to the end.

``DroneWrapper.takeoff`` / ``land`` build the :mod:`dronewrapper.runtime.flight` ``Takeoff`` /
``Landing`` that a service's loop steps (one request to the bridge each, answered once the
manoeuvre has ended), on a :class:`WrapperAircraft` (the wrapper's state, setpoint stream and
service calls), and :func:`fly` steps them on the caller's thread until done. A
:class:`FlightError` becomes the SDK's exception (:func:`drone_error`), with the same text.
"""

from __future__ import annotations

import logging
import threading
from collections.abc import Callable
from concurrent.futures import Future
from typing import Any

from dronewrapper.errors import Cancelled, CommandRefused, DroneError, NoData, NotConnected, Timeout
from dronewrapper.msgs.mavros import State
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

log = logging.getLogger("dronewrapper")

POLL_INTERVAL_S = 0.02
"""How often a blocking take-off or landing looks at the telemetry (s)."""


class WrapperAircraft:
    """A DroneWrapper's side of :class:`~dronewrapper.runtime.flight.Aircraft`.

    Args:
        ns: the vehicle namespace.
        state: the wrapper's newest State holder.
        stop: stops the wrapper's setpoint stream.
        ask: ``ask(service, request, timeout)``: a blocking call that returns the reply or
            raises the runtime's ServiceError / ServiceUnavailable.
    """

    def __init__(
        self,
        ns: str,
        *,
        state: Latest[State],
        stop: Callable[[], None],
        ask: Callable[[Service[Any, Any], Any, float], Any],
    ) -> None:
        self.ns = ns
        self.state = state
        self._stop, self._ask = stop, ask

    def connected_state(self) -> State | None:
        state = self.state.fresh(STATE_FRESH_S)
        return state if state is not None and state.connected else None

    def not_ready_reason(self) -> str:
        return "the bridge's autopilot is not connected"

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


CANCEL_POLL_S = 0.05
"""How often the cancel watcher looks whether the flight has ended (s, real time)."""


def cancel_on(cancel: threading.Event, ended: threading.Event, ask: Callable[[], Any]) -> None:
    """Once ``cancel`` is set before ``ended``, ``ask()`` the bridge to cancel (its running
    take-off or landing ends at once and the aircraft holds where it is); a failed ask is
    logged. Runs on its own thread, since the flight's thread waits on the bridge's reply."""
    while not ended.is_set():
        if cancel.wait(CANCEL_POLL_S):
            if ended.is_set():
                return
            try:
                ask()
            except Exception as exc:  # no bridge, refused: the flight's own error says more
                log.warning("the bridge did not take the cancel: %s", exc)
            return


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
        Cancelled: ``cancelled()`` became true: no further step was taken (the bridge's
            take-off or landing, one request, is ended by the cancel sent meanwhile:
            :func:`cancel_on`).
    """
    what = type(sequence).__name__.lower()
    try:
        while not sequence.step(clock()):
            sleep(interval)
            if cancelled():
                raise Cancelled(f"{what} cancelled")
    except FlightError as exc:
        if cancelled():  # the bridge ended it on our cancel
            raise Cancelled(f"{what} cancelled") from None
        raise drone_error(exc, no_reply) from None
    if cancelled():  # set while the bridge flew it: the bridge's manoeuvre had ended first
        raise Cancelled(f"{what} cancelled (the bridge's {what} had ended first)")
