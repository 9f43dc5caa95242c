"""The safety envelope as data: where an aircraft may fly (ENU m in the home frame, m/s).

Plain data of the contract: the :class:`Envelope` struct, which refuses values no envelope can
have when it is built (a ceiling below :data:`MIN_ALTITUDE_M`, a polygon with fewer than 3
vertices, a breach action it does not know). What an envelope allows or refuses (a target, a
take-off, a breach) is behaviour, not data: :mod:`dronewrapper.envelope` (the checks the SDK
and the bridges share) and :mod:`dronewrapper_bridge_base.breach` (the bridges' breach rule).

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


__all__ = ["BREACH_ACTIONS", "MIN_ALTITUDE_M", "UPPER_BOUNDS", "Envelope", "Polygon"]
