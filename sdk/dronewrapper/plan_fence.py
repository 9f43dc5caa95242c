"""A QGroundControl plan's ``geoFence`` and ``rallyPoints``, and how they fold into the
envelope.

:func:`parse_fence` reads what QGroundControl writes: ``geoFence.polygons`` (``polygon``:
``[[lat, lon], ...]`` degrees, ``inclusion``), ``geoFence.circles`` (``circle.center``
``[lat, lon]`` degrees, ``circle.radius`` m, ``inclusion``), ``geoFence.breachReturn``
(``[lat, lon, alt]``, where ArduPilot flies after a fence breach) and ``rallyPoints.points``
(``[lat, lon, alt]``, alt m above home, where a return may go instead of home).

:func:`rally_waypoints` gives the rally points as NAV_RALLY_POINT items (frame 3, m above
home), which the bridge checks against the envelope and uploads to the autopilot
(MAV_MISSION_TYPE_RALLY) with the mission.

:func:`fold` carries the fence into the bridge's envelope (ENU m from home, so it binds every
setpoint, take-off and mission item, and the bridge uploads it to the autopilot as its fence):
an inclusion zone becomes the envelope's ``fence``, exclusion zones join its ``exclusions``.
A circle becomes a polygon of :data:`CIRCLE_VERTICES` vertices that errs on the safe side: an
inclusion circle's polygon lies inside the circle, an exclusion circle's around it. What the
envelope cannot hold is refused, never dropped: more than one inclusion zone (the envelope
has one fence), an inclusion zone while the envelope already has another fence, and a
breach-return point (the envelope's return flies home) unless the caller accepts returns to
home (``returns_home``). Rally points are not the envelope's: they are uploaded.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import msgspec

from dronewrapper.envelope import Envelope
from dronewrapper.geodesy import to_enu
from dronewrapper.msgs.mission import FRAME_GLOBAL_REL_ALT, NAV_RALLY_POINT, Waypoint

CIRCLE_VERTICES = 24

LatLon = tuple[float, float]


@dataclass(frozen=True)
class Zone:
    """A fence zone in degrees: a polygon (``vertices``) or a circle (``center``, ``radius``
    m); ``inclusion``: the aircraft stays inside it, else outside."""

    inclusion: bool
    vertices: tuple[LatLon, ...] = ()
    center: LatLon | None = None
    radius: float = 0.0

    def describe(self) -> str:
        kind = "inclusion" if self.inclusion else "exclusion"
        if self.center is not None:
            return f"{kind} circle of {self.radius:g} m"
        return f"{kind} polygon of {len(self.vertices)} vertices"


@dataclass(frozen=True)
class PlanFence:
    """A plan's fence zones, breach-return point and rally points (degrees, m)."""

    zones: tuple[Zone, ...] = ()
    breach_return: tuple[float, float, float] | None = None
    rally_points: tuple[tuple[float, float, float], ...] = field(default_factory=tuple)

    @property
    def empty(self) -> bool:
        return not self.zones and self.breach_return is None and not self.rally_points

    @property
    def folds(self) -> bool:
        """Whether anything here goes into the envelope (zones, a breach-return point)."""
        return bool(self.zones) or self.breach_return is not None


def _point(value: Any, size: int, where: str) -> tuple[float, ...]:
    ok = isinstance(value, list) and len(value) >= size
    numbers = value[:size] if ok else []
    if not ok or not all(
        isinstance(v, int | float) and not isinstance(v, bool) and math.isfinite(v) for v in numbers
    ):
        raise ValueError(f"{where}: expected {size} finite numbers, got {value!r}")
    lat, lon = float(numbers[0]), float(numbers[1])
    if abs(lat) > 90 or abs(lon) > 180:
        raise ValueError(f"{where}: ({lat}, {lon}) is not a latitude and longitude")
    return tuple(float(v) for v in numbers)


def parse_fence(document: dict[str, Any]) -> PlanFence:
    """The ``geoFence`` and ``rallyPoints`` of a parsed ``.plan`` document.

    Raises:
        ValueError: a malformed zone or point (the message names it).
    """
    fence = document.get("geoFence") or {}
    rally = document.get("rallyPoints") or {}
    if not isinstance(fence, dict) or not isinstance(rally, dict):
        raise ValueError("geoFence and rallyPoints must be objects")
    zones = []
    for number, entry in enumerate(fence.get("polygons") or []):
        where = f"geoFence.polygons[{number}]"
        vertices = entry.get("polygon") if isinstance(entry, dict) else None
        if not isinstance(vertices, list) or len(vertices) < 3:
            raise ValueError(f"{where}: a polygon needs at least 3 [lat, lon] vertices")
        points = tuple(_point(v, 2, f"{where} vertex {i}") for i, v in enumerate(vertices))
        zones.append(Zone(bool(entry.get("inclusion", True)), vertices=points))  # type: ignore[arg-type]
    for number, entry in enumerate(fence.get("circles") or []):
        where = f"geoFence.circles[{number}]"
        circle = entry.get("circle") if isinstance(entry, dict) else None
        if not isinstance(circle, dict):
            raise ValueError(f"{where}: no circle object")
        lat, lon = _point(circle.get("center"), 2, f"{where} center")
        radius = circle.get("radius")
        if not isinstance(radius, int | float) or not (math.isfinite(radius) and radius > 0):
            raise ValueError(f"{where}: radius must be a positive number of metres")
        zones.append(Zone(bool(entry.get("inclusion", True)), center=(lat, lon), radius=radius))
    breach = fence.get("breachReturn")
    breach_return = _point(breach, 3, "geoFence.breachReturn") if breach is not None else None
    points = tuple(
        _point(p, 3, f"rallyPoints.points[{i}]") for i, p in enumerate(rally.get("points") or [])
    )
    return PlanFence(tuple(zones), breach_return, points)  # type: ignore[arg-type]


def zone_polygon(zone: Zone, home: Sequence[float]) -> list[tuple[float, float]]:
    """``zone`` as a polygon, ENU m from ``home`` (lat, lon degrees): a circle's polygon lies
    inside an inclusion circle and around an exclusion circle."""
    if zone.center is None:
        return [to_enu(home, lat, lon) for lat, lon in zone.vertices]
    cx, cy = to_enu(home, *zone.center)
    step = 2 * math.pi / CIRCLE_VERTICES
    radius = zone.radius if zone.inclusion else zone.radius / math.cos(step / 2)
    return [
        (cx + radius * math.cos(i * step), cy + radius * math.sin(i * step))
        for i in range(CIRCLE_VERTICES)
    ]


def fold(
    fence: PlanFence, envelope: Envelope, home: Sequence[float], *, returns_home: bool = False
) -> Envelope:
    """``envelope`` with ``fence``'s zones carried into it (see module docstring); ``home``:
    home's (lat, lon) degrees.

    Raises:
        ValueError: what the envelope cannot hold, named (nothing is dropped).
    """
    if not returns_home and fence.breach_return is not None:
        raise ValueError(
            "the plan has a geoFence breachReturn point, which is not flown: the envelope's "
            "return flies home. Remove it, or pass returns_home=True to accept returns to home"
        )
    inclusions = [z for z in fence.zones if z.inclusion]
    if len(inclusions) > 1:
        raise ValueError(
            f"the plan's geoFence has {len(inclusions)} inclusion zones "
            f"({', '.join(z.describe() for z in inclusions)}); the envelope holds one"
        )
    fence_polygon = list(envelope.fence)
    if inclusions:
        polygon = zone_polygon(inclusions[0], home)
        if envelope.fence and not _same(envelope.fence, polygon):
            raise ValueError(
                f"the plan's geoFence {inclusions[0].describe()} would replace the envelope's "
                "fence: clear it first (set_envelope(fence=[])) to fly with the plan's"
            )
        fence_polygon = polygon
    exclusions = [list(p) for p in envelope.exclusions]
    for zone in fence.zones:
        if not zone.inclusion:
            polygon = zone_polygon(zone, home)
            if not any(_same(polygon, p) for p in exclusions):
                exclusions.append(polygon)
    return msgspec.structs.replace(envelope, fence=fence_polygon, exclusions=exclusions)


def rally_waypoints(fence: PlanFence) -> list[Waypoint]:
    """``fence``'s rally points as NAV_RALLY_POINT items (degrees, m above home)."""
    return [
        Waypoint(
            frame=FRAME_GLOBAL_REL_ALT,
            command=NAV_RALLY_POINT,
            x_lat=lat,
            y_long=lon,
            z_alt=alt,
            param4=0.0,
        )
        for lat, lon, alt in fence.rally_points
    ]


def _same(a: Sequence[Sequence[float]], b: Sequence[Sequence[float]], tol: float = 0.01) -> bool:
    return len(a) == len(b) and all(
        math.isclose(p[0], q[0], abs_tol=tol) and math.isclose(p[1], q[1], abs_tol=tol)
        for p, q in zip(a, b, strict=True)
    )


__all__ = [
    "CIRCLE_VERTICES",
    "PlanFence",
    "Zone",
    "fold",
    "parse_fence",
    "rally_waypoints",
    "zone_polygon",
]
