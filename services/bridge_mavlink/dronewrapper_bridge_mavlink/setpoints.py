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
reason (:class:`SetpointError`), by the rules every bridge shares
(:mod:`dronewrapper_bridge_base.setpoint_limits`), once, where the setpoint enters the core
(``GuidedCore.on_setpoint``); :func:`to_local_ned` converts what was admitted there and checks
nothing again.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import msgspec

from dronewrapper.msgs.mavros import (
    FRAME_BODY_NED,
    FRAME_LOCAL_NED,
    MASK_MIXED,
    MASK_POSITION,
    MASK_VELOCITY,
    PositionTarget,
)
from dronewrapper_bridge_base import setpoint_limits
from dronewrapper_bridge_base.frames import enu_to_ned, heading_flu_to_enu, yaw_enu_to_ned
from dronewrapper_bridge_base.guided_failsafe import hold_target
from dronewrapper_bridge_base.setpoint_limits import Kind, SetpointError, kind_of
from dronewrapper_bridge_mavlink.modes import AUTOPILOT_ARDUPILOT


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


def validate(target: PositionTarget, limits: Limits = DEFAULT_LIMITS) -> Kind:
    """The control ``target`` asks for, or SetpointError saying what is wrong with it (the
    rules every bridge shares: :mod:`dronewrapper_bridge_base.setpoint_limits`)."""
    return setpoint_limits.validate(target, limits)


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
    """The SET_POSITION_TARGET_LOCAL_NED fields for an admitted ``target`` (one :func:`validate`
    passed at the core's edge, or the bridge's own hold); it is not checked again.

    ``yaw_enu`` is the vehicle's current heading (rad, ENU), used to rotate body velocities;
    ``z_enu`` its current altitude (m, ENU), used for ArduPilot's emulated mixed control.
    """
    kind = kind_of(target)
    if kind is Kind.POSITION:
        p = target.required_position()
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
        error = target.required_position().z - z_enu
        climb = limits.mixed_altitude_gain * error
        climb = max(-limits.mixed_max_climb, min(limits.mixed_max_climb, climb))
        return LocalNedTarget(
            FRAME_LOCAL_NED, MASK_VELOCITY, vx=north, vy=east, vz=-climb, yaw_rate=yaw_rate_ned
        )
    return LocalNedTarget(
        FRAME_LOCAL_NED,
        MASK_MIXED,
        z=-target.required_position().z,
        vx=north,
        vy=east,
        vz=-target.velocity.z,
        yaw_rate=yaw_rate_ned,
    )


def is_velocity_control(kind: Kind) -> bool:
    """True for controls that command a velocity (they expire into a position hold)."""
    return kind is not Kind.POSITION


__all__ = [
    "DEFAULT_LIMITS",
    "Kind",
    "Limits",
    "LocalNedTarget",
    "SetpointError",
    "hold_target",
    "is_velocity_control",
    "to_local_ned",
    "validate",
]
