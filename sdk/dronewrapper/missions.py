"""Go-to, return-to-launch, missions and the safety envelope: :class:`MissionsMixin`, the part
of :class:`~dronewrapper.drone.DroneWrapper` that MAVSDK and DroneKit users look for first.

* ``goto(lat, lon, alt)`` (alt m above home) and ``goto_local(x, y, z)`` (ENU m from home)
  stream a position setpoint in the guided mode and return once the drone is within
  ``tolerance`` (1 m) of the point. The bridge's envelope is checked first, so a point outside
  it raises CommandRefused naming the limit and nothing is sent.
* ``return_to_launch()``: the autopilot's return (the Tello: fly home, land); returns landed.
* ``upload_mission(plan)`` (a QGroundControl ``.plan`` path, or a list of ``(lat, lon,
  alt)``; ``frame="local"``: ``(x, y, z)`` ENU m from home), ``start_mission()``,
  ``pause_mission()``, ``mission_progress()``.
* ``set_envelope(max_altitude=..., max_distance=..., fence=...)``: the bridge's envelope
  (fence: ``[(x, y), ...]`` ENU m from home), which it enforces on every setpoint, take-off
  and mission item, and uploads to the autopilot as its fence.

Home is what the bridge publishes on ``home_position/home``; before it arrives, the local
origin (the Tello's take-off point).
"""

from __future__ import annotations

import logging
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from os import PathLike
from typing import TYPE_CHECKING, Any

import msgspec

from dronewrapper import envelope as env
from dronewrapper import setpoints
from dronewrapper.envelope import Envelope, EnvelopeError
from dronewrapper.errors import CommandRefused, DroneError, InvalidArgument, NoData, Timeout
from dronewrapper.geodesy import to_enu
from dronewrapper.msgs import registry
from dronewrapper.msgs.mavros import (
    LANDED_STATE_ON_GROUND,
    MASK_MIXED,
    MASK_POSITION,
    PositionTarget,
)
from dronewrapper.msgs.mission import (
    EnvelopeSet,
    MissionControl,
    WaypointList,
    WaypointPush,
    WaypointReached,
)
from dronewrapper.plan import PlanError, waypoints_of

if TYPE_CHECKING:
    from dronewrapper.runtime.latest import Latest

log = logging.getLogger("dronewrapper")

GUIDED = {"px4": "OFFBOARD", "ardupilotmega": "GUIDED"}
POLL_S = 0.05


@dataclass(frozen=True)
class MissionProgress:
    """Where the mission stands: ``current`` (the item being flown, 0-based), ``total``
    items, and ``reached`` (the last item reached, -1 before any)."""

    current: int
    total: int
    reached: int

    @property
    def finished(self) -> bool:
        return self.total > 0 and self.reached >= self.total - 1


class MissionsMixin:
    """Missions, go-to and the envelope (see module docstring); mixed into DroneWrapper."""

    def _declare_mission_inputs(self: Any) -> None:
        self._home = self.inputs.latest(registry.HOME_POSITION)
        self._envelope = self.inputs.latest(registry.ENVELOPE)
        self._waypoints: Latest[WaypointList] = self.inputs.latest(registry.MISSION_WAYPOINTS)
        self._reached: Latest[WaypointReached] = self.inputs.latest(registry.MISSION_REACHED)

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
            p = target.position
            if target.type_mask == MASK_POSITION and home is not None:
                env.check_position(envelope, p.x - home.x, p.y - home.y, p.z - home.z)
            elif target.type_mask == MASK_MIXED and home is not None:
                z, ceiling = p.z - home.z, envelope.max_altitude  # its altitude only
                if z > ceiling:
                    reason = f"altitude {z:g} m above the envelope's {ceiling:g} m"
                    raise EnvelopeError(reason, "max_altitude")
        except EnvelopeError as exc:
            raise CommandRefused(what, f"outside the envelope: {exc}", limit=exc.limit) from None

    def _check_takeoff(self: Any, h: float) -> None:
        """CommandRefused when a take-off to ``h`` m climbs above the bridge's envelope (the
        bridge refuses it too; this names the limit before anything is streamed)."""
        envelope = self._envelope.value
        if envelope is None:
            try:
                envelope = self.envelope(timeout=min(2.0, self.service_timeout))
            except DroneError:
                return  # a bridge without an envelope service: it judges alone
        try:
            env.check_takeoff(envelope, h)
        except EnvelopeError as exc:
            raise CommandRefused("takeoff", str(exc), limit=exc.limit) from None

    def _home_local(self: Any) -> tuple[float, float, float]:
        home = self._home.value
        return (0.0, 0.0, 0.0) if home is None else (home.x, home.y, home.z)

    # ------------------------------------------------------------------ go-to

    def goto(
        self: Any,
        lat: float,
        lon: float,
        alt: float,
        *,
        timeout: float = 60.0,
        tolerance: float = 1.0,
    ) -> None:
        """Fly to (``lat``, ``lon``) degrees at ``alt`` m above home; return within
        ``tolerance`` m of it. See :meth:`goto_local` for the errors."""
        lat, lon = setpoints.finite("lat", lat), setpoints.finite("lon", lon)
        if abs(lat) > 90 or abs(lon) > 180:
            raise InvalidArgument(f"goto: ({lat}, {lon}) is not a latitude and longitude")
        home = self._home.value
        if home is None or math.isnan(home.latitude):
            raise NoData(
                f"goto: no home position with latitude and longitude on "
                f"{registry.HOME_POSITION.key(self.ns)} (no GPS, or no bridge): use goto_local"
            )
        east, north = to_enu((home.latitude, home.longitude), lat, lon)
        self.goto_local(east, north, alt, timeout=timeout, tolerance=tolerance)

    def goto_local(
        self: Any,
        x: float,
        y: float,
        z: float,
        *,
        timeout: float = 60.0,
        tolerance: float = 1.0,
    ) -> None:
        """Fly to (``x``, ``y``, ``z``) ENU metres from home, keeping the heading; return once
        within ``tolerance`` m. The position setpoint keeps being streamed afterwards.

        Raises:
            CommandRefused: the point is outside the envelope (the limit is named), the bridge
                refused the setpoint, or the autopilot left the guided mode on the way (a
                breach action, a pilot).
            Timeout: not there within ``timeout`` s.
        """
        x, y, z = (setpoints.finite(name, v) for name, v in (("x", x), ("y", y), ("z", z)))
        try:
            env.check_position(self.envelope(), x, y, z)
        except EnvelopeError as exc:
            raise CommandRefused("goto", str(exc)) from None
        hx, hy, hz = self._home_local()
        target = (hx + x, hy + y, hz + z)
        seen = list(self.status_texts)  # the texts before: a refusal is a new one
        self.set_cmd_pos(*target)
        state = self._require_connected("goto")
        guided = GUIDED.get(state.autopilot)
        if guided is not None and state.mode != guided:
            self.set_mode(guided)
        deadline = self.clock.monotonic() + timeout
        while True:
            position = self.get_position()
            if math.dist(position, target) <= tolerance:
                return
            refused = [
                t.text for t in list(self.status_texts) if "refused" in t.text and t not in seen
            ]
            if refused:
                raise CommandRefused("goto", refused[-1])
            state = self.inputs.state.value
            if guided is not None and state is not None and state.mode != guided:
                raise CommandRefused("goto", f"the autopilot left {guided} for {state.mode}")
            if self.clock.monotonic() >= deadline:
                raise Timeout(
                    f"goto: not within {tolerance:g} m of ({x:g}, {y:g}, {z:g}) after "
                    f"{timeout:g} s; {math.dist(position, target):.1f} m away"
                )
            self.clock.sleep(POLL_S)

    # ------------------------------------------------------------------ return

    def return_to_launch(self: Any, *, timeout: float = 180.0) -> None:
        """Fly home and land (the autopilot's return mode; the Tello flies home at its height
        and lands); return once on the ground and disarmed.

        Raises:
            CommandRefused: the autopilot refused the return.
            Timeout: not landed and disarmed within ``timeout`` s.
        """
        self._require_connected("return_to_launch")
        self.stop_commanding()
        self._command(
            registry.MISSION_CONTROL, MissionControl(action="return"), "return_to_launch", None
        )
        deadline = self.clock.monotonic() + timeout
        while True:
            state, extended = self.inputs.state.value, self.inputs.extended.value
            landed = extended is not None and extended.landed_state == LANDED_STATE_ON_GROUND
            if state is not None and not state.armed and landed:
                return
            if self.clock.monotonic() >= deadline:
                raise Timeout(f"return_to_launch: not landed and disarmed after {timeout:g} s")
            self.clock.sleep(POLL_S)

    # ------------------------------------------------------------------ missions

    def upload_mission(
        self: Any,
        plan: str | PathLike[str] | Mapping[str, Any] | Sequence[Any],
        *,
        frame: str = "global",
        timeout: float = 30.0,
    ) -> int:
        """Upload a mission: a QGroundControl ``.plan`` path (or its parsed JSON), or a list
        of ``(lat, lon, alt)`` (degrees, m above home); ``frame="local"``: ``(x, y, z)`` ENU
        m from home (the Tello's only kind). Returns the number of items.

        Raises:
            InvalidArgument: the plan cannot be read or flown (the message says where).
            CommandRefused: an item is outside the envelope, or the autopilot refused the
                upload (with how many items it took).
        """
        try:
            waypoints = waypoints_of(plan, frame=frame)
        except PlanError as exc:
            raise InvalidArgument(f"upload_mission: {exc}") from None
        reply = self._command(
            registry.MISSION_PUSH, WaypointPush(waypoints=waypoints), "upload_mission", timeout
        )
        return reply.wp_transfered

    def start_mission(self: Any, *, timeout: float | None = None) -> None:
        """Fly the uploaded mission from its current item (after a pause: where it paused).
        Take off first. Raises CommandRefused (no mission, the autopilot's refusal)."""
        self.stop_commanding()
        self._command(
            registry.MISSION_CONTROL, MissionControl(action="start"), "start_mission", timeout
        )

    def pause_mission(self: Any, *, timeout: float | None = None) -> None:
        """Hold where the drone is; :meth:`start_mission` resumes."""
        self._command(
            registry.MISSION_CONTROL, MissionControl(action="pause"), "pause_mission", timeout
        )

    def mission_progress(self: Any) -> MissionProgress:
        """The mission's progress as the bridge last published it."""
        listing = self._waypoints.value
        reached = self._reached.value
        if listing is None:
            raise NoData(f"no mission list yet on {registry.MISSION_WAYPOINTS.key(self.ns)}")
        return MissionProgress(
            current=listing.current_seq,
            total=len(listing.waypoints),
            reached=-1 if reached is None else reached.wp_seq,
        )


def _named(exc: msgspec.ValidationError) -> str:
    """msgspec's message with the field first: ``max_altitude: Expected `float`, got `str```."""
    message, _, path = str(exc).partition(" - at `$.")
    return f"{path.rstrip('`')}: {message}" if path else message


__all__ = ["MissionProgress", "MissionsMixin"]
