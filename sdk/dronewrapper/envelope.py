"""The safety envelope: where an aircraft may fly, and what to do when it is outside.

Pure rules, shared by every bridge (bridge_mavlink for PX4 and ArduPilot, bridge_tello) and
by the SDK, which checks a go-to before it asks. Positions are ENU metres in the home frame
(x east, y north, z up, origin at home); speeds m/s.

* :func:`check_position`: a position target outside the envelope is refused, with the limit
  named ("altitude 500 m above the envelope's 120 m"); nothing is ever clamped.
* :func:`check_takeoff`: a take-off height above ``max_altitude`` is refused.
* :func:`check_velocity`: a velocity above the maximum speeds is refused.
* :func:`breach`: the aircraft's own position is outside the envelope by more than ``margin``
  (wind, a mission, a pilot): the bridge then takes ``breach_action`` (hold, return or land).
* :func:`check_replacement`: a new envelope whose fence contains neither home nor the aircraft
  is refused (it would breach at once, or leave home outside: a return could never end).

``max_altitude`` is at least :data:`MIN_ALTITUDE_M`: a ceiling lower than that leaves no room to
take off and hover above the ground effect, so it is a typo (centimetres, or 0.1 for 10).

The fence is an inclusion polygon (at least 3 vertices, ENU m); exclusion zones are polygons
the aircraft must stay out of. An empty fence means no polygon, only the distance limit.
"""

from __future__ import annotations

import math

import msgspec

BREACH_ACTIONS = ("hold", "return", "land")
MIN_ALTITUDE_M = 1.0
"""The lowest ``max_altitude`` an envelope may have (m above home)."""
UPPER_BOUNDS = {  # beyond these a value is a typo, not an envelope
    "max_altitude": 10_000.0,  # m
    "max_distance": 100_000.0,  # m
    "max_horizontal_speed": 100.0,  # m/s
    "max_vertical_speed": 50.0,  # m/s
}

Polygon = list[tuple[float, float]]


class EnvelopeError(ValueError):
    """A target outside the envelope; the message names the limit, and ``limit`` is the
    envelope's field it is beyond (``max_altitude``, ``fence`` ...)."""

    def __init__(self, message: str, limit: str = "") -> None:
        super().__init__(message)
        self.limit = limit


class Envelope(msgspec.Struct, frozen=True, kw_only=True, forbid_unknown_fields=True):
    """Where the aircraft may fly (ENU m in the home frame, m/s).

    Attributes:
        max_altitude: highest altitude above home (m).
        max_distance: largest horizontal distance from home (m).
        fence: inclusion polygon [(x, y), ...] (ENU m); empty: none.
        exclusions: polygons the aircraft must stay out of (ENU m).
        max_horizontal_speed: largest commanded horizontal speed (m/s).
        max_vertical_speed: largest commanded vertical speed (m/s).
        breach_action: ``hold``, ``return`` or ``land`` when the aircraft is outside.
        margin: how far outside (m) the aircraft may drift before a breach is declared.
    """

    max_altitude: float = 120.0
    max_distance: float = 500.0
    fence: Polygon = msgspec.field(default_factory=list)
    exclusions: list[Polygon] = msgspec.field(default_factory=list)
    max_horizontal_speed: float = 12.0
    max_vertical_speed: float = 5.0
    breach_action: str = "return"
    margin: float = 1.0

    def __post_init__(self) -> None:
        for name, upper in UPPER_BOUNDS.items():
            value = getattr(self, name)
            if isinstance(value, bool) or not (math.isfinite(value) and 0 < value <= upper):
                raise ValueError(f"envelope {name} must be in (0, {upper:g}], got {value!r}")
        if self.max_altitude < MIN_ALTITUDE_M:
            raise ValueError(
                f"envelope max_altitude must be at least {MIN_ALTITUDE_M:g} m above home, "
                f"got {self.max_altitude!r}"
            )
        if not (math.isfinite(self.margin) and 0 <= self.margin <= 50):
            raise ValueError(f"envelope margin must be in [0, 50] m, got {self.margin!r}")
        if self.breach_action not in BREACH_ACTIONS:
            raise ValueError(
                f"envelope breach_action must be one of {', '.join(BREACH_ACTIONS)}, "
                f"got {self.breach_action!r}"
            )
        for label, polygon in (("fence", self.fence), *(("exclusion", p) for p in self.exclusions)):
            if label == "fence" and not polygon:
                continue
            _check_polygon(label, polygon)


def _check_polygon(label: str, polygon: Polygon) -> None:
    if len(polygon) < 3:
        raise ValueError(f"envelope {label} needs at least 3 vertices, got {len(polygon)}")
    for vertex in polygon:
        if len(vertex) != 2 or not all(math.isfinite(v) for v in vertex):
            raise ValueError(f"envelope {label} vertex {vertex!r} must be a finite (x, y)")


def inside(polygon: Polygon, x: float, y: float) -> bool:
    """True when (x, y) is inside ``polygon`` (even-odd rule; ENU m)."""
    result = False
    n = len(polygon)
    for i in range(n):
        x1, y1 = polygon[i]
        x2, y2 = polygon[(i - 1) % n]
        if (y1 > y) != (y2 > y) and x < (x2 - x1) * (y - y1) / (y2 - y1) + x1:
            result = not result
    return result


def distance_outside(polygon: Polygon, x: float, y: float) -> float:
    """Distance (m) from (x, y) to the polygon's boundary; 0 inside."""
    if inside(polygon, x, y):
        return 0.0
    best = math.inf
    n = len(polygon)
    for i in range(n):
        (ax, ay), (bx, by) = polygon[i], polygon[(i + 1) % n]
        dx, dy = bx - ax, by - ay
        length2 = dx * dx + dy * dy
        t = 0.0 if length2 == 0 else max(0.0, min(1.0, ((x - ax) * dx + (y - ay) * dy) / length2))
        best = min(best, math.hypot(x - (ax + t * dx), y - (ay + t * dy)))
    return best


def metres(value: float) -> str:
    """A length as people read it: ``4.5 m``, ``1113.19 m``, ``8843.4 km`` (never
    ``8.84341e+06 m``)."""
    if abs(value) >= 10_000:
        return f"{value / 1000:.1f} km"
    return f"{value:g} m"


def _plain(value: float) -> str:
    return f"{value:.0f}" if abs(value) >= 100_000 else f"{value:g}"


def violated(
    envelope: Envelope, x: float, y: float, z: float, margin: float = 0.0
) -> tuple[str, str]:
    """(the envelope's field, the reason) when (x, y, z) (ENU m from home) is beyond a limit
    by more than ``margin`` m, else ("", "")."""
    if z > envelope.max_altitude + margin:
        reason = f"altitude {metres(z)} above the envelope's {envelope.max_altitude:g} m"
        return "max_altitude", reason
    distance = math.hypot(x, y)
    if distance > envelope.max_distance + margin:
        return "max_distance", (
            f"distance {metres(distance)} from home beyond the envelope's "
            f"{envelope.max_distance:g} m"
        )
    where = f"({_plain(x)}, {_plain(y)}) m"
    if envelope.fence and distance_outside(envelope.fence, x, y) > margin:
        return "fence", f"position {where} outside the envelope's fence"
    for number, zone in enumerate(envelope.exclusions, start=1):
        if inside(zone, x, y):
            return "exclusions", f"position {where} inside the envelope's exclusion zone {number}"
    return "", ""


def violation(envelope: Envelope, x: float, y: float, z: float, margin: float = 0.0) -> str:
    """The limit (x, y, z) (ENU m from home) is beyond by more than ``margin`` m, or ""."""
    return violated(envelope, x, y, z, margin)[1]


def check_position(envelope: Envelope, x: float, y: float, z: float) -> None:
    """EnvelopeError naming the limit when the target (x, y, z) (ENU m from home) is outside."""
    limit, reason = violated(envelope, x, y, z)
    if reason:
        raise EnvelopeError(reason, limit)


def check_takeoff(envelope: Envelope, height: float) -> None:
    """EnvelopeError when a take-off to ``height`` m above home climbs above the envelope."""
    if math.isfinite(height) and height > envelope.max_altitude:
        raise EnvelopeError(
            f"take-off altitude {height:g} m above the envelope's {envelope.max_altitude:g} m",
            "max_altitude",
        )


def check_velocity(envelope: Envelope, vx: float, vy: float, vz: float) -> None:
    """EnvelopeError when a commanded velocity (m/s) is faster than the envelope allows."""
    horizontal = math.hypot(vx, vy)
    if horizontal > envelope.max_horizontal_speed:
        raise EnvelopeError(
            f"horizontal speed {horizontal:g} m/s above the envelope's "
            f"{envelope.max_horizontal_speed:g} m/s",
            "max_horizontal_speed",
        )
    if abs(vz) > envelope.max_vertical_speed:
        raise EnvelopeError(
            f"vertical speed {abs(vz):g} m/s above the envelope's "
            f"{envelope.max_vertical_speed:g} m/s",
            "max_vertical_speed",
        )


def check_replacement(envelope: Envelope, aircraft: tuple[float, float] | None) -> None:
    """EnvelopeError (limit ``fence``) when ``envelope``'s fence contains neither home (the
    origin) nor the aircraft at ``aircraft`` (x, y ENU m from home; None: not known)."""
    if not envelope.fence or inside(envelope.fence, 0.0, 0.0):
        return
    if aircraft is not None and inside(envelope.fence, *aircraft):
        return
    where = "" if aircraft is None else f" nor the aircraft at ({aircraft[0]:g}, {aircraft[1]:g}) m"
    raise EnvelopeError(f"the fence contains neither home{where}", "fence")


def breach(envelope: Envelope, x: float, y: float, z: float) -> str:
    """The limit the aircraft at (x, y, z) (ENU m from home) has crossed by more than the
    envelope's margin, or "" while it is inside."""
    return violation(envelope, x, y, z, envelope.margin)


class BreachMonitor:
    """Declares a breach once per excursion: :meth:`update` returns the reason the first time
    the aircraft is found outside, and again only after it has been back inside."""

    def __init__(self) -> None:
        self.outside = False
        self.breaches = 0
        self.limit = ""  # the envelope's field the last breach crossed

    def update(self, envelope: Envelope, position: tuple[float, float, float]) -> str:
        """The breach to act on now ("" when none or already acted on)."""
        limit, reason = violated(envelope, *position, envelope.margin)
        if not reason:
            if self.outside and not violation(envelope, *position):
                self.outside = False
            return ""
        if self.outside:
            return ""
        self.outside = True
        self.breaches += 1
        self.limit = limit
        return reason


__all__ = [
    "BREACH_ACTIONS",
    "BreachMonitor",
    "Envelope",
    "EnvelopeError",
    "breach",
    "check_position",
    "check_replacement",
    "check_takeoff",
    "check_velocity",
    "distance_outside",
    "inside",
    "metres",
    "violated",
    "violation",
]
