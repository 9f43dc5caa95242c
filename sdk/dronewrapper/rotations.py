"""Rotations on plain floats: angle wrapping, quaternions and Z-Y-X Euler angles.

Quaternions are ``(x, y, z, w)`` tuples, Hamilton convention as in ROS and Eigen; Euler angles
are intrinsic Z-Y-X (yaw, then pitch, then roll), radians. Frame-free: which frames a rotation
joins (ENU/FLU, NED/FRD) is said by the caller (the bridges' ``frames`` modules, the SDK's
telemetry, the simulator).
"""

from __future__ import annotations

import math

Vec3 = tuple[float, float, float]
Quat = tuple[float, float, float, float]  # x, y, z, w


def wrap_pi(angle: float) -> float:
    """``angle`` wrapped to [-pi, pi)."""
    return (angle + math.pi) % (2.0 * math.pi) - math.pi


def quat_multiply(a: Quat, b: Quat) -> Quat:
    """The Hamilton product ``a * b`` (apply ``b`` first, then ``a``)."""
    ax, ay, az, aw = a
    bx, by, bz, bw = b
    return (
        aw * bx + ax * bw + ay * bz - az * by,
        aw * by - ax * bz + ay * bw + az * bx,
        aw * bz + ax * by - ay * bx + az * bw,
        aw * bw - ax * bx - ay * by - az * bz,
    )


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
    """(roll, pitch, yaw) of a quaternion, Z-Y-X convention; inverse of :func:`quat_from_rpy`."""
    x, y, z, w = q
    roll = math.atan2(2.0 * (w * x + y * z), 1.0 - 2.0 * (x * x + y * y))
    sinp = max(-1.0, min(1.0, 2.0 * (w * y - z * x)))
    pitch = math.asin(sinp)
    yaw = math.atan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z))
    return (roll, pitch, yaw)


def quat_normalize(q: Quat) -> Quat:
    """``q`` scaled to unit length (identity if it is zero)."""
    n = math.sqrt(sum(c * c for c in q))
    if n == 0.0 or not math.isfinite(n):
        return (0.0, 0.0, 0.0, 1.0)
    return (q[0] / n, q[1] / n, q[2] / n, q[3] / n)


def rotate(q: Quat, v: Vec3) -> Vec3:
    """``v`` rotated by the unit quaternion ``q`` (body -> world when q is the attitude)."""
    x, y, z, w = q
    vx, vy, vz = v
    # t = 2 * cross(q.xyz, v); v' = v + w * t + cross(q.xyz, t)
    tx = 2.0 * (y * vz - z * vy)
    ty = 2.0 * (z * vx - x * vz)
    tz = 2.0 * (x * vy - y * vx)
    return (
        vx + w * tx + (y * tz - z * ty),
        vy + w * ty + (z * tx - x * tz),
        vz + w * tz + (x * ty - y * tx),
    )


def rotate_inverse(q: Quat, v: Vec3) -> Vec3:
    """``v`` rotated by the inverse of ``q`` (world -> body when q is the attitude)."""
    return rotate((-q[0], -q[1], -q[2], q[3]), v)
