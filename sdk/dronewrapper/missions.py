"""Go-to, return-to-launch, missions and the safety envelope: :class:`MissionsMixin`, the part
of :class:`~dronewrapper.drone.DroneWrapper` that MAVSDK and DroneKit users look for first.

* ``goto(lat, lon, alt)`` (alt m above home) and ``goto_local(x, y, z)`` (ENU m from home):
  one request to the bridge (``{ns}/dronewrapper/goto``), which flies there its aircraft's way
  and answers once within ``tolerance`` (1 m); a point outside the envelope the wrapper holds
  raises CommandRefused naming the limit before anything is sent.
* ``return_to_launch()``: one request (``{ns}/dronewrapper/return``), answered on the ground.
* ``upload_mission(plan)`` (a QGroundControl ``.plan`` path, or a list of ``(lat, lon,
  alt)``; ``frame="local"``: ``(x, y, z)`` ENU m from home), ``start_mission()``,
  ``pause_mission()``, ``resume_mission()`` (one request each, ``{ns}/dronewrapper/mission``),
  ``mission_progress()``.
* ``set_envelope(max_altitude=..., max_distance=..., fence=...)``: the bridge's envelope
  (fence: ``[(x, y), ...]`` ENU m from home), which it enforces on every setpoint, take-off
  and mission item, and uploads to the autopilot as its fence.

Home is what the bridge publishes on ``home_position/home``; before it arrives, a go-to waits
for it (a few seconds), then raises NoData: never a guess. No autopilot's mode is named here
and no status text is read: the bridge answers each action with its typed result.
"""

from __future__ import annotations

import logging
import math
import threading
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from os import PathLike
from typing import TYPE_CHECKING, Any

import msgspec

from dronewrapper import envelope as env
from dronewrapper import plan_fence, setpoints
from dronewrapper.beat import Beat
from dronewrapper.envelope import Envelope, EnvelopeError
from dronewrapper.errors import CommandRefused, DroneError, InvalidArgument, NoData
from dronewrapper.msgs import registry
from dronewrapper.msgs.flight import GotoRequest
from dronewrapper.msgs.mavros import MASK_MIXED, MASK_POSITION, PositionTarget
from dronewrapper.msgs.mission import (
    EnvelopeSet,
    HomePosition,
    WaypointList,
    WaypointPush,
    WaypointReached,
)
from dronewrapper.plan import PlanError, load_plan
from dronewrapper.plan_fence import PlanFence
from dronewrapper.runtime.flight import Goto, MissionStep, Return

if TYPE_CHECKING:
    from dronewrapper.runtime.latest import Latest

log = logging.getLogger("dronewrapper")
NAV_COMMANDS_START = 16  # MAV_CMD_NAV_WAYPOINT: the NAV_* commands are 16-99


@dataclass(frozen=True)
class MissionProgress:
    """Where the mission stands: ``current`` (the item being flown, 0-based), ``total``
    items, ``reached`` (the last item reached, 0-based; None until one is heard reached) and
    ``reached_items`` (every item reported reached since the upload, in order, each once:
    PX4 and our simulator report the items that fly somewhere, not speed or camera items).
    ``last_flown`` is the last item that flies somewhere (a ``NAV_*`` command); None: the last
    item."""

    current: int
    total: int
    reached: int | None = None
    reached_items: tuple[int, ...] = ()
    last_flown: int | None = None

    @property
    def reached_count(self) -> int:
        """How many distinct items have been reached."""
        return len(self.reached_items)

    @property
    def finished(self) -> bool:
        """The last item that flies somewhere was reached. The speed, camera and payload items
        after it (a QGroundControl survey ends with its camera trigger off) are never reported
        reached, so they are not waited for; a mission with no such item never reads
        finished."""
        end = self.total - 1 if self.last_flown is None else self.last_flown
        return self.total > 0 and self.reached is not None and self.reached >= end


class MissionsMixin:
    """Missions, go-to and the envelope (see module docstring); mixed into DroneWrapper."""

    def _declare_mission_inputs(self: Any) -> None:
        self._home = self.inputs.latest(registry.HOME_POSITION)
        self._envelope = self.inputs.latest(registry.ENVELOPE)
        self._waypoints: Latest[WaypointList] = self.inputs.latest(registry.MISSION_WAYPOINTS)
        self._reached: Latest[WaypointReached] = self.inputs.latest(registry.MISSION_REACHED)
        self._beat: Beat | None = None  # started by the first go-to, return or mission
        self._reached_items: list[int] = []  # every item reached since the last upload
        self._last_reached: int | None = None  # the item last reached since the last upload
        self._reached.listen(self._on_reached)

    def _on_reached(self: Any) -> None:
        reached = self._reached.value
        if reached is None:
            return
        self._last_reached = reached.wp_seq
        if reached.wp_seq not in self._reached_items:
            self._reached_items.append(reached.wp_seq)

    # ------------------------------------------------------------------ envelope

    def envelope(self: Any, *, timeout: float | None = None) -> Envelope:
        """The envelope the bridge enforces now."""
        return self._envelope_call(EnvelopeSet(), "envelope", timeout).envelope

    def set_envelope(self: Any, *, timeout: float | None = None, **limits: Any) -> Envelope:
        """Change the bridge's envelope: any of ``max_altitude`` (m above home, at least
        :data:`~dronewrapper.envelope.MIN_ALTITUDE_M`), ``max_distance`` (m from home),
        ``fence`` (``[(x, y), ...]`` ENU m from home; ``[]`` none; it must contain home or
        the drone), ``exclusions``, ``max_horizontal_speed``, ``max_vertical_speed`` (m/s),
        ``breach_action`` (``hold``, ``return``, ``land``), ``margin`` (m). The others stay.
        Returns the envelope in force. The new envelope outlives this program: the next one
        is warned on connect, and :meth:`reset_envelope` puts the bridge's configured one back.

        Raises:
            InvalidArgument: an unknown field, or a value of the wrong type or out of range (the
                message names the field; nothing is changed).
            CommandRefused: the bridge refused it (a fence containing neither home nor the
                drone).
        """
        current = self.envelope(timeout=timeout)
        unknown = set(limits) - set(Envelope.__struct_fields__)
        if unknown:
            raise InvalidArgument(f"set_envelope: unknown field(s) {sorted(unknown)}")
        fields = {**msgspec.structs.asdict(current), **limits}
        try:
            wanted = msgspec.convert(fields, Envelope)
        except msgspec.ValidationError as exc:
            raise InvalidArgument(f"set_envelope: {_named(exc)}") from None
        return self._envelope_call(EnvelopeSet(envelope=wanted), "set_envelope", timeout).envelope

    def reset_envelope(self: Any, *, timeout: float | None = None) -> Envelope:
        """Put the bridge's configured envelope back (undo every :meth:`set_envelope`);
        returns it."""
        return self._envelope_call(EnvelopeSet(reset=True), "reset_envelope", timeout).envelope

    def _envelope_call(self: Any, request: EnvelopeSet, what: str, timeout: float | None):
        """One envelope/set call; the envelope in force is then held for the setpoint checks."""
        reply = self._command(registry.ENVELOPE_SET, request, what, timeout)
        self._envelope.update(reply.envelope)
        return reply

    def _warn_of_envelope(self: Any) -> None:
        """On connect: fetch the envelope in force (held for the setpoint checks) and warn when
        a commander set it rather than the bridge's configuration (it outlived its program)."""
        try:
            reply = self._envelope_call(EnvelopeSet(), "envelope", min(2.0, self.service_timeout))
        except DroneError:
            return  # a bridge without an envelope service: it judges alone
        if reply.set_by:
            e = reply.envelope
            fence = f"a fence of {len(e.fence)} vertices" if e.fence else "no fence"
            log.warning(
                "%s: the envelope in force was set by %r, not the bridge's configuration: "
                "max_altitude %g m, max_distance %g m, %s, breach_action %s; "
                "reset_envelope() puts the configured one back",
                self.ns,
                reply.set_by,
                e.max_altitude,
                e.max_distance,
                fence,
                e.breach_action,
            )

    def _check_setpoint(self: Any, target: PositionTarget, what: str) -> None:
        """CommandRefused, the limit named, when ``target`` is outside the envelope held (the
        bridge would refuse it); a position needs home too. Nothing held: the bridge judges,
        and its refusal arrives on :attr:`refusals`."""
        envelope, home = self._envelope.value, self._home.value
        if envelope is None:
            return
        try:
            if target.type_mask != MASK_POSITION:
                v = target.velocity
                env.check_velocity(envelope, v.x, v.y, v.z)
            if target.type_mask == MASK_POSITION and home is not None:
                p = target.required_position()
                env.check_position(envelope, p.x - home.x, p.y - home.y, p.z - home.z)
            elif target.type_mask == MASK_MIXED and home is not None:
                z = target.required_position().z - home.z  # its altitude only
                ceiling = envelope.max_altitude
                if z > ceiling:
                    reason = f"altitude {z:g} m above the envelope's {ceiling:g} m"
                    raise EnvelopeError(reason, "max_altitude")
        except EnvelopeError as exc:
            raise CommandRefused(what, f"outside the envelope: {exc}", limit=exc.limit) from None

    def _held_envelope(self: Any) -> Envelope | None:
        """The bridge's envelope as last published, else asked for (None: no envelope service)."""
        envelope = self._envelope.value
        if envelope is None:
            try:
                envelope = self.envelope(timeout=min(2.0, self.service_timeout))
            except DroneError:
                return None
        return envelope

    def _check_takeoff(self: Any, h: float) -> None:
        """CommandRefused when a take-off to ``h`` m climbs above the bridge's envelope (the
        bridge refuses it too; this names the limit before anything is streamed)."""
        envelope = self._held_envelope()
        if envelope is None:
            return  # a bridge without an envelope service: it judges alone
        try:
            env.check_takeoff(envelope, h)
        except EnvelopeError as exc:
            raise CommandRefused("takeoff", str(exc), limit=exc.limit) from None

    def home(self: Any) -> HomePosition:
        """Home as the bridge last published it: ``latitude``, ``longitude`` (degrees; NaN
        without GPS), ``altitude`` (m AMSL) and ``x``, ``y``, ``z`` in the local frame (the one
        of get_position). It is the origin of goto_local, goto's altitude and local missions.

        Raises:
            NoData: no home published yet.
        """
        home = self._home.value
        if home is None:
            raise NoData(f"no home position yet on {registry.HOME_POSITION.key(self.ns)}")
        return home

    def _watch_key(self: Any) -> str:
        """The name of this process for the bridge (``{ns}/alive/{node}``), its beat started
        (:mod:`dronewrapper.beat`): once the beats stop, the bridge ends an unattended go-to,
        return or mission as for a lost commander."""
        if self._beat is None:
            key = registry.ALIVE.key(self.node.ns, service=self.node.name)
            publisher = self.node.publisher(
                registry.COMMANDER_BEAT, key=registry.COMMANDER_BEAT.key(self.ns)
            )
            self._beat = Beat(publisher.put, key, self.clock)
            self._beat_publisher = publisher
        self._beat.start()
        return self._beat.key

    # ------------------------------------------------------------------ go-to

    def goto(
        self: Any,
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
            raise InvalidArgument(f"goto: ({lat}, {lon}) is not a latitude and longitude")
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
        self: Any,
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
        envelope = self._held_envelope()
        if envelope is not None:
            try:
                env.check_position(envelope, x, y, z)
            except EnvelopeError as exc:
                raise CommandRefused("goto", str(exc), limit=exc.limit) from None
        request = GotoRequest(
            x=x, y=y, z=z, timeout=timeout, tolerance=tolerance, watch=self._watch_key()
        )
        self._goto(request, cancel)

    def _goto(self: Any, request: GotoRequest, cancel: threading.Event | None) -> None:
        now = self.clock.monotonic()
        self._require_connected("goto")
        sequence = Goto(self._aircraft, request, now, call_timeout=self.service_timeout)
        self._fly(sequence, cancel)

    # ------------------------------------------------------------------ return

    def return_to_launch(
        self: Any, *, timeout: float = 180.0, cancel: threading.Event | None = None
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
        self._require_connected("return_to_launch")
        sequence = Return(
            self._aircraft, timeout, now, watch=self._watch_key(), call_timeout=self.service_timeout
        )
        self._fly(sequence, cancel)

    # ------------------------------------------------------------------ missions

    def upload_mission(
        self: Any,
        plan: str | PathLike[str] | Mapping[str, Any] | Sequence[Any],
        *,
        frame: str = "global",
        returns_home: bool = False,
        timeout: float = 30.0,
    ) -> int:
        """Upload a mission: a QGroundControl ``.plan`` path (or its parsed JSON), or a list
        of ``(lat, lon, alt)`` (degrees, m above home); ``frame="local"``: ``(x, y, z)`` ENU
        m from home (the Tello's only kind). Returns the number of items.

        A plan's ``geoFence`` is folded into the envelope first (:mod:`dronewrapper.plan_fence`;
        it stays after the mission, put back if the upload fails); a breach-return point is
        refused unless ``returns_home`` accepts returns to home. A plan's rally points are
        uploaded with it as the autopilot's (checked against the envelope; a plan without
        them clears the autopilot's; a list of points leaves them as they are); a backend
        without rally points (the Tello) refuses a plan that has some.

        Raises:
            InvalidArgument: the plan cannot be read or flown, or its fence cannot be held.
            NoData: the plan has a fence and home's position is not known yet.
            CommandRefused: an item or rally point is outside the envelope, or the autopilot
                refused the upload (naming the item it refused and its command).
        """
        try:
            loaded = load_plan(plan, frame=frame)
        except PlanError as exc:
            raise InvalidArgument(f"upload_mission: {exc}") from None
        before = self._fold(loaded.fence, returns_home, timeout) if loaded.fence.folds else None
        document = isinstance(plan, str | PathLike | Mapping)
        rally = plan_fence.rally_waypoints(loaded.fence) if document else None
        push = WaypointPush(waypoints=loaded.waypoints, rally=rally)
        try:
            reply = self._command(registry.MISSION_PUSH, push, "upload_mission", timeout)
        except DroneError:
            if before is not None:
                self._command(
                    registry.ENVELOPE_SET, EnvelopeSet(envelope=before), "upload_mission", timeout
                )
            raise
        self._reached_items.clear()  # the last mission's items are not this one's
        self._last_reached = None
        return reply.wp_transfered

    def _fold(self: Any, fence: PlanFence, returns_home: bool, timeout: float) -> Envelope:
        """Carry a plan's fence into the bridge's envelope; returns the envelope before."""
        home = self._home.value
        if home is None or math.isnan(home.latitude):
            raise NoData("upload_mission: the plan has a fence, and home is not known yet")
        current = self.envelope(timeout=timeout)
        try:
            wanted = plan_fence.fold(
                fence, current, (home.latitude, home.longitude), returns_home=returns_home
            )
        except ValueError as exc:
            raise InvalidArgument(f"upload_mission: {exc}") from None
        if wanted != current:
            self._command(
                registry.ENVELOPE_SET, EnvelopeSet(envelope=wanted), "upload_mission", timeout
            )
        return current

    def start_mission(self: Any, *, timeout: float = 10.0) -> None:
        """Fly the uploaded mission from its current item; returns once the drone flies it
        (follow it with :meth:`mission_progress`). Take off first. If this program ends
        before the mission, the bridge lets the mission finish, then returns home (its
        ``unattended_action``, docs/design.md).

        Raises:
            CommandRefused: no mission uploaded, not flying, or the autopilot's refusal.
        """
        self._mission("start", timeout)

    def pause_mission(self: Any, *, timeout: float = 10.0) -> None:
        """Hold where the drone is; :meth:`resume_mission` goes on. CommandRefused when no
        mission is being flown."""
        self._mission("pause", timeout)

    def resume_mission(self: Any, *, timeout: float = 10.0) -> None:
        """Go on with the mission from where it paused (CommandRefused as
        :meth:`start_mission`)."""
        self._mission("resume", timeout)

    def _mission(self: Any, action: str, timeout: float) -> None:
        now = self.clock.monotonic()
        self._require_connected(f"{action}_mission")
        watch = "" if action == "pause" else self._watch_key()
        sequence = MissionStep(
            self._aircraft, action, timeout, now, watch=watch, call_timeout=self.service_timeout
        )
        self._fly(sequence, None)

    def mission_progress(self: Any) -> MissionProgress:
        """The mission's progress as the bridge last published it."""
        listing = self._waypoints.value
        if listing is None:
            raise NoData(f"no mission list yet on {registry.MISSION_WAYPOINTS.key(self.ns)}")
        return MissionProgress(
            current=listing.current_seq,
            total=len(listing.waypoints),
            reached=self._last_reached,
            reached_items=tuple(self._reached_items),
            last_flown=_last_flown(listing),
        )


def _last_flown(listing: WaypointList) -> int | None:
    """The index of the last item that flies somewhere (MAV_CMD_NAV_*: 16-99), or None."""
    flown = [i for i, wp in enumerate(listing.waypoints) if NAV_COMMANDS_START <= wp.command < 100]
    return flown[-1] if flown else None


def _named(exc: msgspec.ValidationError) -> str:
    """msgspec's message with the field first: ``max_altitude: Expected `float`, got `str```."""
    message, _, path = str(exc).partition(" - at `$.")
    return f"{path.rstrip('`')}: {message}" if path else message


__all__ = ["MissionProgress", "MissionsMixin"]
