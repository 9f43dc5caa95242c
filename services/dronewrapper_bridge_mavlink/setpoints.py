"""PositionTarget (ENU / FLU, DESIGN's three controls) -> SET_POSITION_TARGET_LOCAL_NED fields.

Every target goes to the autopilot in MAV_FRAME_LOCAL_NED (1), on PX4 and ArduPilot alike: body
velocities are rotated by the current heading here, so "vx" means forward on every drone and
no autopilot-specific body frame (PX4's 8, ArduPilot's 9) is ever sent.

Accepted controls (type_mask, coordinate_frame):

* 3064 in frame 1: position x, y, z (ENU m) and yaw (ENU rad).
* 1991 in frame 8: velocity vx, vy, vz (FLU m/s) and yaw_rate (rad/s, CCW positive);
  in frame 1 the velocity is local ENU instead.
* 1987 in frame 8: vx, vy (FLU m/s), altitude z (ENU m) and yaw_rate. PX4 takes this mask
  natively; ArduCopter ignores a partial position, so for it the altitude is held by the bridge
  with a vertical-speed command proportional to the altitude error.

Anything else, NaN/inf in a used field or values outside :class:`Limits` is refused with a
reason (:class:`SetpointError`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from enum import Enum

import msgspec

from dronewrapper.msgs.geometry import Point
from dronewrapper.msgs.mavros import (
    FRAME_BODY_NED,
    FRAME_LOCAL_NED,
    MASK_MIXED,
    MASK_POSITION,
    MASK_VELOCITY,
    PositionTarget,
)
from dronewrapper_bridge_mavlink.frames import enu_to_ned, heading_flu_to_enu, yaw_enu_to_ned
from dronewrapper_bridge_mavlink.modes import AUTOPILOT_ARDUPILOT


class SetpointError(ValueError):
    """A PositionTarget the bridge refuses; the message says why."""


class Kind(Enum):
    """Which of DESIGN's controls a target is."""

    POSITION = "position"
    VELOCITY = "velocity"
    MIXED = "mixed"


class Limits(msgspec.Struct, frozen=True, kw_only=True, forbid_unknown_fields=True):
    """Bounds on accepted setpoints (m, m/s, rad/s). Beyond them a setpoint is refused. Also
    the ``limits`` section of the bridge's config, as is."""

    max_distance: float = 10_000.0  # |x|, |y| of position targets, m from the local origin
    min_altitude: float = -1_000.0  # ENU z, m
    max_altitude: float = 10_000.0
    max_horizontal_speed: float = 20.0  # m/s, norm of (vx, vy)
    max_vertical_speed: float = 10.0  # m/s
    max_yaw_rate: float = 2.0 * math.pi  # rad/s
    mixed_altitude_gain: float = 1.0  # 1/s, ArduPilot mixed control: vz = gain * altitude error
    mixed_max_climb: float = 1.5  # m/s, clamp of that vz


DEFAULT_LIMITS = Limits()


@dataclass(frozen=True)
class LocalNedTarget:
    """The fields of SET_POSITION_TARGET_LOCAL_NED (local NED, m, m/s, rad, rad/s)."""

    coordinate_frame: int
    type_mask: int
    x: float = 0.0
    y: float = 0.0
    z: float = 0.0
    vx: float = 0.0
    vy: float = 0.0
    vz: float = 0.0
    yaw: float = 0.0
    yaw_rate: float = 0.0


_FRAMES_FOR_MASK = {
    MASK_POSITION: (FRAME_LOCAL_NED,),
    MASK_VELOCITY: (FRAME_BODY_NED, FRAME_LOCAL_NED),
    MASK_MIXED: (FRAME_BODY_NED, FRAME_LOCAL_NED),
}
_KIND_FOR_MASK = {
    MASK_POSITION: Kind.POSITION,
    MASK_VELOCITY: Kind.VELOCITY,
    MASK_MIXED: Kind.MIXED,
}


def _finite(name: str, value: float) -> float:
    if not isinstance(value, int | float) or not math.isfinite(value):
        raise SetpointError(f"{name} must be a finite number, got {value!r}")
    return float(value)


def validate(target: PositionTarget, limits: Limits = DEFAULT_LIMITS) -> Kind:
    """The control ``target`` asks for, or SetpointError saying what is wrong with it."""
    mask, frame = target.type_mask, target.coordinate_frame
    if mask not in _KIND_FOR_MASK:
        raise SetpointError(
            f"type_mask {mask} is not supported; use {MASK_POSITION} (position + yaw), "
            f"{MASK_VELOCITY} (velocity + yaw rate) or {MASK_MIXED} (vx, vy, altitude z, yaw rate)"
        )
    if frame not in _FRAMES_FOR_MASK[mask]:
        allowed = " or ".join(str(f) for f in _FRAMES_FOR_MASK[mask])
        raise SetpointError(
            f"coordinate_frame {frame} is not valid with type_mask {mask}: use {allowed}"
        )
    kind = _KIND_FOR_MASK[mask]
    p, v = target.position, target.velocity
    if kind in (Kind.POSITION, Kind.MIXED) and p is msgspec.UNSET:
        raise SetpointError(f"position is required with type_mask {mask}")
    if kind is Kind.POSITION:
        x, y = _finite("position.x", p.x), _finite("position.y", p.y)
        z = _finite("position.z", p.z)
        _finite("yaw", target.yaw)
        if abs(x) > limits.max_distance or abs(y) > limits.max_distance:
            raise SetpointError(
                f"position ({x:g}, {y:g}) is farther than {limits.max_distance:g} m from the origin"
            )
        _check_altitude(z, limits)
        return kind
    vx, vy = _finite("velocity.x", v.x), _finite("velocity.y", v.y)
    vz = _finite("velocity.z", v.z)
    yaw_rate = _finite("yaw_rate", target.yaw_rate)
    if math.hypot(vx, vy) > limits.max_horizontal_speed:
        raise SetpointError(
            f"horizontal speed {math.hypot(vx, vy):g} m/s exceeds {limits.max_horizontal_speed:g}"
        )
    if abs(vz) > limits.max_vertical_speed:
        raise SetpointError(f"vertical speed {vz:g} m/s exceeds {limits.max_vertical_speed:g}")
    if abs(yaw_rate) > limits.max_yaw_rate:
        raise SetpointError(f"yaw_rate {yaw_rate:g} rad/s exceeds {limits.max_yaw_rate:g}")
    if kind is Kind.MIXED:
        _check_altitude(_finite("position.z", p.z), limits)
    return kind


def _check_altitude(z: float, limits: Limits) -> None:
    if not limits.min_altitude <= z <= limits.max_altitude:
        raise SetpointError(
            f"altitude z={z:g} m is outside [{limits.min_altitude:g}, {limits.max_altitude:g}]"
        )


def _horizontal_enu(target: PositionTarget, yaw_enu: float) -> tuple[float, float]:
    v = target.velocity
    if target.coordinate_frame == FRAME_BODY_NED:
        return heading_flu_to_enu(v.x, v.y, yaw_enu)
    return (v.x, v.y)


def to_local_ned(
    target: PositionTarget,
    *,
    autopilot: str,
    yaw_enu: float,
    z_enu: float,
    limits: Limits = DEFAULT_LIMITS,
) -> LocalNedTarget:
    """The SET_POSITION_TARGET_LOCAL_NED fields for a valid ``target`` (see :func:`validate`).

    ``yaw_enu`` is the vehicle's current heading (rad, ENU), used to rotate body velocities;
    ``z_enu`` its current altitude (m, ENU), used for ArduPilot's emulated mixed control.
    """
    kind = validate(target, limits)
    if kind is Kind.POSITION:
        p = target.position
        n, e, d = enu_to_ned((p.x, p.y, p.z))
        return LocalNedTarget(
            FRAME_LOCAL_NED, MASK_POSITION, x=n, y=e, z=d, yaw=yaw_enu_to_ned(target.yaw)
        )
    east, north = _horizontal_enu(target, yaw_enu)
    yaw_rate_ned = -target.yaw_rate  # CCW-positive (ENU) -> CW-positive (NED)
    if kind is Kind.VELOCITY:
        return LocalNedTarget(
            FRAME_LOCAL_NED,
            MASK_VELOCITY,
            vx=north,
            vy=east,
            vz=-target.velocity.z,
            yaw_rate=yaw_rate_ned,
        )
    if autopilot == AUTOPILOT_ARDUPILOT:
        error = target.position.z - z_enu
        climb = limits.mixed_altitude_gain * error
        climb = max(-limits.mixed_max_climb, min(limits.mixed_max_climb, climb))
        return LocalNedTarget(
            FRAME_LOCAL_NED, MASK_VELOCITY, vx=north, vy=east, vz=-climb, yaw_rate=yaw_rate_ned
        )
    return LocalNedTarget(
        FRAME_LOCAL_NED,
        MASK_MIXED,
        z=-target.position.z,
        vx=north,
        vy=east,
        vz=-target.velocity.z,
        yaw_rate=yaw_rate_ned,
    )


def hold_target(position_enu: tuple[float, float, float], yaw_enu: float) -> PositionTarget:
    """A position + yaw PositionTarget (mask 3064, ENU) that holds ``position_enu``."""
    x, y, z = position_enu
    return PositionTarget(
        coordinate_frame=FRAME_LOCAL_NED,
        type_mask=MASK_POSITION,
        position=Point(x=x, y=y, z=z),
        yaw=yaw_enu,
    )


def is_velocity_control(kind: Kind) -> bool:
    """True for controls that command a velocity (they expire into a position hold)."""
    return kind is not Kind.POSITION
