"""The safety envelope's checks: is a target, a take-off or a velocity inside the envelope.

Pure rules, shared by every bridge (bridge_mavlink for PX4 and ArduPilot, bridge_tello) and
by the SDK, which checks a go-to before it asks. Positions are ENU metres in the home frame
(x east, y north, z up, origin at home); speeds m/s. The :class:`Envelope` itself is the
contract's plain data (:mod:`dronewrapper.msgs.envelope`, named here too); the bridges' own
rules (a breach of the aircraft's position, a replaced envelope) are
:mod:`dronewrapper_bridge_base.breach`.

* :func:`check_position`: a position target outside the envelope is refused, with the limit
  named ("altitude 500 m above the envelope's 120 m"); nothing is ever clamped.
* :func:`check_takeoff`: a take-off height above ``max_altitude`` is refused.
* :func:`check_velocity`: a velocity above the maximum speeds is refused.
* :func:`violated`: the limit a point is beyond (by more than a margin), and why.
"""

from __future__ import annotations

import math

from dronewrapper.msgs.envelope import (
    BREACH_ACTIONS,
    MIN_ALTITUDE_M,
    UPPER_BOUNDS,
    Envelope,
    Polygon,
)


class EnvelopeError(ValueError):
    """A target outside the envelope; the message names the limit, and ``limit`` is the
    envelope's field it is beyond (``max_altitude``, ``fence`` ...)."""

    def __init__(self, message: str, limit: str = "") -> None:
        super().__init__(message)
        self.limit = limit


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


__all__ = [
    "BREACH_ACTIONS",
    "MIN_ALTITUDE_M",
    "UPPER_BOUNDS",
    "Envelope",
    "EnvelopeError",
    "Polygon",
    "check_position",
    "check_takeoff",
    "check_velocity",
    "distance_outside",
    "inside",
    "metres",
    "violated",
    "violation",
]
