"""Which of the three controls a PositionTarget asks for, and whether a bridge may fly it.

Every bridge refuses the same things in the same words before anything reaches an aircraft:
a type_mask other than the three controls of docs/design.md, a coordinate_frame that control
does not take, a missing position, NaN/inf/bool in a used field, and values beyond the
bridge's bounds. The bounds are any object with the fields of :class:`Bounds` (:class:`Limits`
and bridge_mavlink's extension of it, bridge_tello's ``StickScale``), in ENU metres, m/s and rad/s.

==========  ==========================  ===========================================
type_mask   coordinate_frame            fields checked
==========  ==========================  ===========================================
3064        FRAME_LOCAL_NED (1)         position x, y, z (ENU m), yaw
1991        FRAME_BODY_NED (8) or 1     velocity vx, vy, vz, yaw_rate
1987        FRAME_BODY_NED (8) or 1     velocity vx, vy, vz, yaw_rate; position z
==========  ==========================  ===========================================
"""

from __future__ import annotations

import math
from enum import Enum
from typing import Protocol

import msgspec

from dronewrapper.msgs import mavros


class SetpointError(ValueError):
    """A PositionTarget a bridge refuses; the message says why, and ``limit`` names the field
    or bound it breaks (``type_mask``, ``position.x``, ``max_horizontal_speed`` ...)."""

    def __init__(self, message: str, limit: str = "") -> None:
        super().__init__(message)
        self.limit = limit


class Kind(Enum):
    """Which of docs/design.md's controls a target is."""

    POSITION = "position"
    VELOCITY = "velocity"
    MIXED = "mixed"


class Bounds(Protocol):
    """What a bridge accepts (m from the local origin, ENU m, m/s, rad/s)."""

    @property
    def max_distance(self) -> float: ...  # |x| and |y| of position targets
    @property
    def min_altitude(self) -> float: ...  # ENU z
    @property
    def max_altitude(self) -> float: ...
    @property
    def max_horizontal_speed(self) -> float: ...  # norm of (vx, vy)
    @property
    def max_vertical_speed(self) -> float: ...
    @property
    def max_yaw_rate(self) -> float: ...


class Limits(msgspec.Struct, frozen=True, kw_only=True, forbid_unknown_fields=True):
    """The :class:`Bounds` of a bridge to an autopilot, as its config's ``limits`` section:
    beyond them a setpoint is refused (m, m/s, rad/s)."""

    max_distance: float = 10_000.0  # |x|, |y| of position targets, m from the local origin
    min_altitude: float = -1_000.0  # ENU z, m
    max_altitude: float = 10_000.0
    max_horizontal_speed: float = 20.0  # m/s, norm of (vx, vy)
    max_vertical_speed: float = 10.0  # m/s
    max_yaw_rate: float = 2.0 * math.pi  # rad/s


KIND_OF_MASK = {
    mavros.MASK_POSITION: Kind.POSITION,
    mavros.MASK_VELOCITY: Kind.VELOCITY,
    mavros.MASK_MIXED: Kind.MIXED,
}
FRAMES_OF_MASK = {
    mavros.MASK_POSITION: (mavros.FRAME_LOCAL_NED,),
    mavros.MASK_VELOCITY: (mavros.FRAME_BODY_NED, mavros.FRAME_LOCAL_NED),
    mavros.MASK_MIXED: (mavros.FRAME_BODY_NED, mavros.FRAME_LOCAL_NED),
}


def kind_of(target: mavros.PositionTarget) -> Kind:
    """The control an admitted ``target`` asks for, read from its type_mask alone: for a
    target :func:`validate` admitted at the bridge's edge, or one the bridge built (its own
    hold). Nothing is checked again here; KeyError for a mask that is no control at all."""
    return KIND_OF_MASK[target.type_mask]


def finite_field(name: str, value: object) -> float:
    """``value`` as a float if it is a finite number (not a bool), else SetpointError."""
    if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value):
        raise SetpointError(f"{name} must be a finite number, got {value!r}", name)
    return float(value)


def validate(target: mavros.PositionTarget, bounds: Bounds) -> Kind:
    """The control ``target`` asks for, or SetpointError saying what is wrong with it."""
    mask, frame = target.type_mask, target.coordinate_frame
    if mask not in KIND_OF_MASK:
        raise SetpointError(
            f"type_mask {mask} is not supported; use {mavros.MASK_POSITION} (position + yaw), "
            f"{mavros.MASK_VELOCITY} (velocity + yaw rate) or {mavros.MASK_MIXED} "
            "(vx, vy, altitude z, yaw rate)",
            "type_mask",
        )
    if frame not in FRAMES_OF_MASK[mask]:
        allowed = " or ".join(str(f) for f in FRAMES_OF_MASK[mask])
        raise SetpointError(
            f"coordinate_frame {frame} is not valid with type_mask {mask}: use {allowed}",
            "coordinate_frame",
        )
    kind = KIND_OF_MASK[mask]
    v = target.velocity
    if kind in (Kind.POSITION, Kind.MIXED) and target.position is msgspec.UNSET:
        raise SetpointError(f"position is required with type_mask {mask}", "position")
    if kind is Kind.POSITION:
        p = target.required_position()
        x, y = finite_field("position.x", p.x), finite_field("position.y", p.y)
        z = finite_field("position.z", p.z)
        finite_field("yaw", target.yaw)
        if abs(x) > bounds.max_distance or abs(y) > bounds.max_distance:
            raise SetpointError(
                f"position ({x:g}, {y:g}) is farther than {bounds.max_distance:g} m "
                "from the origin",
                "max_distance",
            )
        _check_altitude(z, bounds)
        return kind
    vx, vy = finite_field("velocity.x", v.x), finite_field("velocity.y", v.y)
    vz = finite_field("velocity.z", v.z)
    yaw_rate = finite_field("yaw_rate", target.yaw_rate)
    if math.hypot(vx, vy) > bounds.max_horizontal_speed:
        raise SetpointError(
            f"horizontal speed {math.hypot(vx, vy):g} m/s exceeds {bounds.max_horizontal_speed:g}",
            "max_horizontal_speed",
        )
    if abs(vz) > bounds.max_vertical_speed:
        raise SetpointError(
            f"vertical speed {vz:g} m/s exceeds {bounds.max_vertical_speed:g}", "max_vertical_speed"
        )
    if abs(yaw_rate) > bounds.max_yaw_rate:
        raise SetpointError(
            f"yaw_rate {yaw_rate:g} rad/s exceeds {bounds.max_yaw_rate:g}", "max_yaw_rate"
        )
    if kind is Kind.MIXED:
        _check_altitude(finite_field("position.z", target.required_position().z), bounds)
    return kind


def _check_altitude(z: float, bounds: Bounds) -> None:
    if not bounds.min_altitude <= z <= bounds.max_altitude:
        raise SetpointError(
            f"altitude z={z:g} m is outside [{bounds.min_altitude:g}, {bounds.max_altitude:g}]",
            "min_altitude" if z < bounds.min_altitude else "max_altitude",
        )
