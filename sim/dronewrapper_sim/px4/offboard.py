"""SET_POSITION_TARGET_LOCAL_NED as PX4 reads it: frames, type mask, NED -> the sim's ENU.

PX4 accepts only MAV_FRAME_LOCAL_NED (1) and MAV_FRAME_BODY_NED (8). Every other frame (7
LOCAL_OFFSET_NED, 9 BODY_OFFSET_NED, 12 BODY_FRD, ...) is refused with the STATUSTEXT
"SET_POSITION_TARGET_LOCAL_NED coordinate frame N unsupported". In BODY_NED, velocity and
acceleration are rotated by the current heading only (vz stays "down", roll and pitch are
ignored); positions stay local. A set type-mask bit means "ignore this field"; an ignored or
non-finite field is "not controlled" (NaN), as in PX4's trajectory setpoint.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from pymavlink.dialects.v20 import common as mavlink

from dronewrapper_sim.frames import rotate_by_yaw, yaw_ned_to_enu

SUPPORTED_FRAMES = (mavlink.MAV_FRAME_LOCAL_NED, mavlink.MAV_FRAME_BODY_NED)

IGNORE_ALL = 0xFFF & ~mavlink.POSITION_TARGET_TYPEMASK_FORCE_SET
IGNORE_POSITION = (
    mavlink.POSITION_TARGET_TYPEMASK_X_IGNORE,
    mavlink.POSITION_TARGET_TYPEMASK_Y_IGNORE,
    mavlink.POSITION_TARGET_TYPEMASK_Z_IGNORE,
)
IGNORE_VELOCITY = (
    mavlink.POSITION_TARGET_TYPEMASK_VX_IGNORE,
    mavlink.POSITION_TARGET_TYPEMASK_VY_IGNORE,
    mavlink.POSITION_TARGET_TYPEMASK_VZ_IGNORE,
)
IGNORE_ACCELERATION = (
    mavlink.POSITION_TARGET_TYPEMASK_AX_IGNORE,
    mavlink.POSITION_TARGET_TYPEMASK_AY_IGNORE,
    mavlink.POSITION_TARGET_TYPEMASK_AZ_IGNORE,
)

NAN = float("nan")


@dataclass(frozen=True)
class OffboardSetpoint:
    """A setpoint in the sim's frames: local ENU (m, m/s, m/s^2), yaw ENU (rad, CCW from east),
    yaw rate (rad/s, CCW). NaN = not controlled. ``non_finite`` counts used fields that were
    NaN/inf in the message (PX4 treats them as not controlled)."""

    position: tuple[float, float, float]
    velocity: tuple[float, float, float]
    acceleration: tuple[float, float, float]
    yaw: float
    yaw_rate: float
    frame: int
    type_mask: int
    non_finite: int = 0

    @property
    def uses_position(self) -> bool:
        return any(math.isfinite(v) for v in self.position)


@dataclass(frozen=True)
class Refusal:
    """A setpoint PX4 drops; ``statustext`` is what it says about it (None: silently)."""

    reason: str
    statustext: str | None = None


def _pick(mask: int, bit: int, value: float) -> tuple[float, int]:
    if mask & bit:
        return NAN, 0
    if not math.isfinite(value):
        return NAN, 1
    return float(value), 0


def parse(
    frame: int,
    type_mask: int,
    pos_ned: tuple[float, float, float],
    vel_ned: tuple[float, float, float],
    acc_ned: tuple[float, float, float],
    yaw_ned: float,
    yaw_rate_ned: float,
    current_yaw_ned: float,
) -> OffboardSetpoint | Refusal:
    """Interpret one SET_POSITION_TARGET_LOCAL_NED (NED fields as sent) like PX4 does.

    ``current_yaw_ned`` is the vehicle's heading (rad, from north clockwise), used to rotate
    body-frame velocities.
    """
    if frame not in SUPPORTED_FRAMES:
        return Refusal(
            f"frame {frame} unsupported",
            f"SET_POSITION_TARGET_LOCAL_NED coordinate frame {frame} unsupported",
        )
    if (type_mask & IGNORE_ALL) == IGNORE_ALL:
        return Refusal("every field ignored by the type mask")
    bad = 0
    p = []
    for bit, value in zip(IGNORE_POSITION, pos_ned, strict=False):
        v, b = _pick(type_mask, bit, value)
        p.append(v)
        bad += b
    v_ned = []
    for bit, value in zip(IGNORE_VELOCITY, vel_ned, strict=False):
        v, b = _pick(type_mask, bit, value)
        v_ned.append(v)
        bad += b
    a_ned = []
    for bit, value in zip(IGNORE_ACCELERATION, acc_ned, strict=False):
        v, b = _pick(type_mask, bit, value)
        a_ned.append(v)
        bad += b
    yaw, b = _pick(type_mask, mavlink.POSITION_TARGET_TYPEMASK_YAW_IGNORE, yaw_ned)
    bad += b
    yaw_rate, b = _pick(type_mask, mavlink.POSITION_TARGET_TYPEMASK_YAW_RATE_IGNORE, yaw_rate_ned)
    bad += b
    if frame == mavlink.MAV_FRAME_BODY_NED:
        # heading frame: x forward, y right, z down; rotate the horizontal part by the yaw
        v_ned[0], v_ned[1] = rotate_by_yaw(v_ned[0], v_ned[1], current_yaw_ned)
        a_ned[0], a_ned[1] = rotate_by_yaw(a_ned[0], a_ned[1], current_yaw_ned)
    return OffboardSetpoint(
        position=(p[1], p[0], -p[2]),
        velocity=(v_ned[1], v_ned[0], -v_ned[2]),
        acceleration=(a_ned[1], a_ned[0], -a_ned[2]),
        yaw=yaw_ned_to_enu(yaw) if math.isfinite(yaw) else NAN,
        yaw_rate=-yaw_rate if math.isfinite(yaw_rate) else NAN,
        frame=frame,
        type_mask=type_mask,
        non_finite=bad,
    )
