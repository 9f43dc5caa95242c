"""A DroneWrapper's long actions, blocking: take-off, landing, go-to, return, mission steps.

Each is one request to the bridge, which flies it its aircraft's way and answers once it has
ended: the :mod:`dronewrapper.client.flight` sequence a service's loop steps, stepped here on
the caller's thread until done (:func:`fly`), on the drone client (its calls answered inline,
since this thread waits anyway). A ``cancel`` event set from another thread asks the bridge to
end the manoeuvre (:func:`cancel_on`; the aircraft holds where it is) and raises
:class:`~dronewrapper.errors.Cancelled`. A :class:`~dronewrapper.client.flight.FlightError`
becomes the SDK's exception (:func:`drone_error`) with the same text. A go-to, a return and a
mission name this process for the bridge (its beat, :mod:`dronewrapper.beat`): once the beats
stop, the bridge ends them as for a lost commander. Heights in metres above the take-off point,
go-to points in ENU metres from home or in degrees, time on the node's clock (s).
"""

from __future__ import annotations

import logging
import threading
from collections.abc import Callable
from typing import Any

from dronewrapper import errors, setpoints
from dronewrapper.beat import Beat
from dronewrapper.client import DroneClient
from dronewrapper.client.flight import (
    FlightError,
    FlightSequence,
    Goto,
    Landing,
    MissionStep,
    NoPosition,
    NoReply,
    Return,
    StepRefused,
    Takeoff,
    TooLate,
)
from dronewrapper.commands import NoReply as NoReplyError
from dronewrapper.envelope_guard import EnvelopeGuard
from dronewrapper.msgs import registry
from dronewrapper.msgs.flight import CancelRequest, GotoRequest
from dronewrapper.msgs.mavros import State
from dronewrapper.runtime.contract import Declared

log = logging.getLogger("dronewrapper")

POLL_INTERVAL_S = 0.02
"""How often a blocking long action looks whether it has ended (s, node clock)."""
CANCEL_POLL_S = 0.05
"""How often the cancel watcher looks whether the flight has ended (s, real time)."""


class Flights:
    """The blocking long actions of one drone (see the module doc); a part a DroneWrapper owns.

    Args:
        client: the drone client, with inline calls (the flight sequences' aircraft).
        guard: the drone's envelope (a take-off or go-to outside it is refused unsent).
        require_connected: ``require_connected(what)``: the connected State, or NotConnected
            saying why ``what`` cannot be done.
        no_reply: the error for a call nobody answered.
        service_timeout: seconds a reply may take beyond the manoeuvre's own timeout.
    """

    def __init__(
        self,
        client: DroneClient,
        guard: EnvelopeGuard,
        *,
        require_connected: Callable[[str], State],
        no_reply: NoReplyError,
        service_timeout: float,
    ) -> None:
        self.client = client
        self.guard = guard
        self.clock = client.clock
        self.require_connected = require_connected
        self.no_reply = no_reply
        self.service_timeout = service_timeout
        self.beat: Beat | None = None  # started by the first go-to, return or mission
        self._beat_publisher: Declared | None = None

    def takeoff(
        self,
        h: float = 3.0,
        *,
        timeout: float = 30.0,
        tolerance: float = 0.1,
        cancel: threading.Event | None = None,
    ) -> None:
        """Take off to ``h`` metres above the take-off point and return there.

        One request to the bridge, which flies the take-off its aircraft's way (PX4: OFFBOARD
        on its own held setpoint, arm, climb; ArduPilot: GUIDED, arm, TAKEOFF; Tello: takeoff,
        then up to ``h``) and answers once there; the aircraft then holds there by itself
        until commanded. Idempotent: already flying, nothing is done (a warning says so).

        Raises:
            CommandRefused: a step was refused (the autopilot's reason is in the message), or
                the autopilot disarmed or left the mode during the climb.
            Timeout: the altitude was not reached within ``timeout`` seconds.
            NotConnected: no bridge / autopilot.
            Cancelled: ``cancel`` was set (from another thread): no further step, and the
                setpoint stream stopped (the bridge holds position).
        """
        h = setpoints.finite("h", h)
        if h <= 0:
            raise errors.InvalidArgument(f"h must be > 0 m, got {h}")
        now = self.clock.monotonic()
        self.require_connected("takeoff")
        self.guard.check_takeoff(h, self._quick())  # above the envelope: refused, limit named
        kwargs = {"tolerance": tolerance, "call_timeout": self.service_timeout}
        self._fly(Takeoff(self.client, h, timeout, now, **kwargs), cancel)

    def land(self, *, timeout: float = 60.0, cancel: threading.Event | None = None) -> None:
        """Land where the drone is and return when it is on the ground and disarmed.

        Stops the setpoint stream, then one request to the bridge, which lands here (no GPS
        needed) and answers once on the ground and disarmed.

        Raises:
            CommandRefused: the autopilot refused to land (its reason is in the message).
            Timeout: not on the ground and disarmed within ``timeout`` seconds.
            Cancelled: ``cancel`` was set (see :meth:`takeoff`).
        """
        now = self.clock.monotonic()
        self.require_connected("land")
        self._fly(Landing(self.client, timeout, now, call_timeout=self.service_timeout), cancel)

    def goto(
        self,
        lat: float,
        lon: float,
        alt: float,
        *,
        timeout: float = 60.0,
        tolerance: float = 1.0,
        cancel: threading.Event | None = None,
    ) -> None:
        """Fly to (``lat``, ``lon``) degrees at ``alt`` m above home and hold there; return
        within ``tolerance`` m of it. See :meth:`goto_local` for the errors (NoData: home has
        no latitude and longitude)."""
        lat, lon = setpoints.finite("lat", lat), setpoints.finite("lon", lon)
        alt = setpoints.finite("alt", alt)
        if abs(lat) > 90 or abs(lon) > 180:
            raise errors.InvalidArgument(f"goto: ({lat}, {lon}) is not a latitude and longitude")
        request = GotoRequest(
            latitude=lat,
            longitude=lon,
            z=alt,
            timeout=timeout,
            tolerance=tolerance,
            watch=self._watch_key(),
        )
        self._goto(request, cancel)

    def goto_local(
        self,
        x: float,
        y: float,
        z: float,
        *,
        timeout: float = 60.0,
        tolerance: float = 1.0,
        cancel: threading.Event | None = None,
    ) -> None:
        """Fly to (``x``, ``y``, ``z``) ENU metres from home (:meth:`home`: where the autopilot
        set it, PX4 and ArduPilot where they armed, so a take-off elsewhere moves it; local
        positions keep their origin) and hold there, keeping the heading;
        return once within ``tolerance`` m. One request to the bridge, which flies it and
        answers at the end; the drone then holds the point by itself until commanded.

        Raises:
            CommandRefused: not flying (take off first), the point is outside the envelope
                (the limit is named), or the autopilot refused or left the guided mode on the
                way (a breach action, a pilot).
            NoData: home is not known (the bridge waits a few seconds for it).
            Timeout: not there within ``timeout`` s (the drone then holds where it is).
            Cancelled: ``cancel`` was set (the drone holds where it is).
        """
        x, y, z = (setpoints.finite(name, v) for name, v in (("x", x), ("y", y), ("z", z)))
        self.guard.check_goto(x, y, z, self._quick())
        request = GotoRequest(
            x=x, y=y, z=z, timeout=timeout, tolerance=tolerance, watch=self._watch_key()
        )
        self._goto(request, cancel)

    def _goto(self, request: GotoRequest, cancel: threading.Event | None) -> None:
        now = self.clock.monotonic()
        self.require_connected("goto")
        sequence = Goto(self.client, request, now, call_timeout=self.service_timeout)
        self._fly(sequence, cancel)

    def return_to_launch(
        self, *, timeout: float = 180.0, cancel: threading.Event | None = None
    ) -> None:
        """Fly home and land (the autopilot's return, its altitude kept under the envelope's
        ceiling by the bridge; the Tello flies home at its height and lands); return once on
        the ground and disarmed.

        Raises:
            CommandRefused: not flying, or the autopilot refused or left the return.
            Timeout: not landed and disarmed within ``timeout`` s.
            Cancelled: ``cancel`` was set (the drone holds where it is).
        """
        now = self.clock.monotonic()
        self.require_connected("return_to_launch")
        sequence = Return(
            self.client, timeout, now, watch=self._watch_key(), call_timeout=self.service_timeout
        )
        self._fly(sequence, cancel)

    def start_mission(self, *, timeout: float = 10.0) -> None:
        """Fly the uploaded mission from its current item; returns once the drone flies it
        (follow it with :meth:`mission_progress`). Take off first. If this program ends
        before the mission, the bridge lets the mission finish, then returns home (its
        ``unattended_action``, docs/design.md).

        Raises:
            CommandRefused: no mission uploaded, not flying, or the autopilot's refusal.
        """
        self._mission("start", timeout)

    def pause_mission(self, *, timeout: float = 10.0) -> None:
        """Hold where the drone is; :meth:`resume_mission` goes on. CommandRefused when no
        mission is being flown."""
        self._mission("pause", timeout)

    def resume_mission(self, *, timeout: float = 10.0) -> None:
        """Go on with the mission from where it paused (CommandRefused as
        :meth:`start_mission`)."""
        self._mission("resume", timeout)

    def _mission(self, action: str, timeout: float) -> None:
        now = self.clock.monotonic()
        self.require_connected(f"{action}_mission")
        watch = "" if action == "pause" else self._watch_key()
        sequence = MissionStep(
            self.client, action, timeout, now, watch=watch, call_timeout=self.service_timeout
        )
        self._fly(sequence, None)

    def _quick(self) -> float:
        """The timeout of a question asked on the way (the envelope): at most 2 s."""
        return min(2.0, self.service_timeout)

    def _watch_key(self) -> str:
        """The name of this process for the bridge (``{ns}/alive/{node}``), its beat started:
        once the beats stop, the bridge ends an unattended go-to, return or mission as for a
        lost commander."""
        if self.beat is None:
            node = self.client.node
            key = registry.ALIVE.key(node.ns, service=node.name)
            publisher = node.publisher(
                registry.COMMANDER_BEAT, key=registry.COMMANDER_BEAT.key(self.client.ns)
            )
            self.beat = Beat(publisher.put, key, self.clock)
            self._beat_publisher = publisher
        self.beat.start()
        return self.beat.key

    def _fly(self, sequence: FlightSequence, cancel: threading.Event | None) -> None:
        """Step ``sequence`` to its end, waiting on the node's clock (or until ``cancel``)."""
        clock, cancel = self.clock, cancel or threading.Event()
        ended = threading.Event()
        watcher = threading.Thread(
            target=cancel_on,
            args=(cancel, ended, self._ask_cancel),
            name="dronewrapper-cancel",
            daemon=True,
        )
        watcher.start()
        try:
            fly(
                sequence,
                clock=clock.monotonic,
                sleep=lambda seconds: clock.wait(cancel, seconds),
                no_reply=self.no_reply,
                cancelled=cancel.is_set,
            )
        except errors.Cancelled:
            self.client.stop()
            raise
        finally:
            ended.set()
            watcher.join(timeout=self.service_timeout + 1.0)

    def _ask_cancel(self) -> None:
        """Ask the bridge to end its running take-off, landing, go-to or return (it holds where
        it is)."""
        self.client.ask(registry.FLIGHT_CANCEL, CancelRequest(reason="the caller cancelled"), 2.0)

    def close(self) -> None:
        """Stop the beat (the bridge then ends an unattended go-to, return or mission)."""
        try:
            if self.beat is not None:
                self.beat.close()
            if self._beat_publisher is not None:
                self._beat_publisher.undeclare()
        except Exception as exc:  # a session already closed by its owner
            log.debug("close the beat: %s", exc)


def drone_error(exc: FlightError, no_reply: NoReplyError) -> errors.DroneError:
    """The SDK's exception for a failed step; ``no_reply(what, key, timeout)`` tells a missing
    bridge (NotConnected) from a silent one (Timeout)."""
    if isinstance(exc, StepRefused):
        return errors.CommandRefused(exc.command, exc.reason, exc.result)
    if isinstance(exc, NoReply):
        return no_reply(exc.command, exc.key, exc.timeout)
    if isinstance(exc, TooLate):
        return errors.Timeout(str(exc))
    if isinstance(exc, NoPosition):
        return errors.NoData(str(exc))
    return errors.NotConnected(str(exc))


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
    no_reply: NoReplyError,
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
                raise errors.Cancelled(f"{what} cancelled")
    except FlightError as exc:
        if cancelled():  # the bridge ended it on our cancel
            raise errors.Cancelled(f"{what} cancelled") from None
        raise drone_error(exc, no_reply) from None
    if cancelled():  # set while the bridge flew it: the bridge's manoeuvre had ended first
        raise errors.Cancelled(f"{what} cancelled (the bridge's {what} had ended first)")
