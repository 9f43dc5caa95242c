"""Frame helpers for the Tello: its aircraft angles (degrees) <-> ENU/FLU quaternions.

Quaternions are (x, y, z, w) tuples, Hamilton convention like ROS. Angles in radians unless a
name says ``_deg``.

The Tello reports aircraft Euler angles as MAVLink/NED does: roll positive right side down,
pitch positive nose up, yaw positive clockwise seen from above, 0 at its reference heading
(the heading at power-on: a Tello has no compass). The local ENU frame (``odom``) is fixed at the
take-off point with its x axis along ``reference_yaw`` (ENU yaw of the power-on heading, default
0: x along the power-on heading, as ROS odometry starts), so ``yaw_enu = reference_yaw - yaw``;
roll stays and pitch changes sign (FRD -> FLU), as MAVROS converts.
"""

from __future__ import annotations

import math

Vec3 = tuple[float, float, float]
Quat = tuple[float, float, float, float]  # x, y, z, w


def wrap_pi(angle: float) -> float:
    """``angle`` wrapped to [-pi, pi)."""
    return (angle + math.pi) % (2.0 * math.pi) - math.pi


def yaw_tello_to_enu(yaw_deg: float, reference_yaw: float = 0.0) -> float:
    """The Tello's yaw (degrees, clockwise from its reference heading) as ENU yaw (rad, CCW);
    ``reference_yaw`` is the ENU yaw of the reference heading (rad)."""
    return wrap_pi(reference_yaw - math.radians(yaw_deg))


def quat_from_rpy(roll: float, pitch: float, yaw: float) -> Quat:
    """Quaternion of intrinsic Z-Y-X (yaw, then pitch, then roll) angles, as ROS/Eigen do."""
    cr, sr = math.cos(roll / 2.0), math.sin(roll / 2.0)
    cp, sp = math.cos(pitch / 2.0), math.sin(pitch / 2.0)
    cy, sy = math.cos(yaw / 2.0), math.sin(yaw / 2.0)
    return (
        sr * cp * cy - cr * sp * sy,
        cr * sp * cy + sr * cp * sy,
        cr * cp * sy - sr * sp * cy,
        cr * cp * cy + sr * sp * sy,
    )


def rpy_from_quat(q: Quat) -> Vec3:
    """(roll, pitch, yaw) of a quaternion (intrinsic Z-Y-X), radians."""
    x, y, z, w = q
    roll = math.atan2(2.0 * (w * x + y * z), 1.0 - 2.0 * (x * x + y * y))
    pitch = math.asin(max(-1.0, min(1.0, 2.0 * (w * y - z * x))))
    yaw = math.atan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z))
    return roll, pitch, yaw


def attitude_enu(
    roll_deg: float, pitch_deg: float, yaw_deg: float, reference_yaw: float = 0.0
) -> Quat:
    """The Tello's attitude angles (degrees, FRD convention) as body FLU in local ENU."""
    return quat_from_rpy(
        math.radians(roll_deg),
        -math.radians(pitch_deg),
        yaw_tello_to_enu(yaw_deg, reference_yaw),
    )


def rotate(q: Quat, v: Vec3) -> Vec3:
    """``v`` rotated by ``q`` (a body vector expressed in the parent frame)."""
    x, y, z, w = q
    # v' = v + 2w (u x v) + 2 u x (u x v), u = (x, y, z)
    tx = 2.0 * (y * v[2] - z * v[1])
    ty = 2.0 * (z * v[0] - x * v[2])
    tz = 2.0 * (x * v[1] - y * v[0])
    return (
        v[0] + w * tx + (y * tz - z * ty),
        v[1] + w * ty + (z * tx - x * tz),
        v[2] + w * tz + (x * ty - y * tx),
    )


def rotate_inverse(q: Quat, v: Vec3) -> Vec3:
    """``v`` (parent frame) expressed in the body frame of ``q``."""
    return rotate((-q[0], -q[1], -q[2], q[3]), v)


def enu_to_heading_flu(east: float, north: float, yaw_enu: float) -> tuple[float, float]:
    """A horizontal ENU vector as (forward, left) of a body at heading ``yaw_enu`` (level)."""
    c, s = math.cos(yaw_enu), math.sin(yaw_enu)
    return (c * east + s * north, -s * east + c * north)
