"""Frame conversions between MAVLink (NED / FRD) and DroneWrapper (ENU / FLU), as MAVROS does.

Local frames: NED (x north, y east, z down) <-> ENU (x east, y north, z up).
Body frames: FRD (forward, right, down) <-> FLU (forward, left, up).
Quaternions are (x, y, z, w) tuples, Hamilton convention like ROS. Angles in radians.

The orientation conversion is MAVROS's ``ftf::transform_orientation_ned_enu`` followed by
``transform_orientation_aircraft_baselink``: ``q_enu_flu = Q_NED_ENU * q_ned_frd * Q_FRD_FLU``
with ``Q_NED_ENU = rpy(pi, 0, pi/2)`` and ``Q_FRD_FLU = rpy(pi, 0, 0)``. In Euler terms:
roll stays, pitch and yaw-rate change sign, yaw_enu = pi/2 - yaw_ned.
"""

from __future__ import annotations

import math

Vec3 = tuple[float, float, float]
Quat = tuple[float, float, float, float]  # x, y, z, w


def ned_to_enu(v: Vec3) -> Vec3:
    """A local NED vector (north, east, down) as ENU (east, north, up)."""
    return (v[1], v[0], -v[2])


def enu_to_ned(v: Vec3) -> Vec3:
    """A local ENU vector as NED (the same swap-and-negate; it is its own inverse)."""
    return (v[1], v[0], -v[2])


def frd_to_flu(v: Vec3) -> Vec3:
    """A body FRD vector (forward, right, down) as FLU (forward, left, up)."""
    return (v[0], -v[1], -v[2])


def flu_to_frd(v: Vec3) -> Vec3:
    """A body FLU vector as FRD (its own inverse)."""
    return (v[0], -v[1], -v[2])


def wrap_pi(angle: float) -> float:
    """``angle`` wrapped to [-pi, pi)."""
    return (angle + math.pi) % (2.0 * math.pi) - math.pi


def yaw_ned_to_enu(yaw_ned: float) -> float:
    """Heading clockwise from north (NED) -> counter-clockwise from east (ENU), wrapped."""
    return wrap_pi(math.pi / 2.0 - yaw_ned)


def yaw_enu_to_ned(yaw_enu: float) -> float:
    """Heading counter-clockwise from east (ENU) -> clockwise from north (NED), wrapped."""
    return wrap_pi(math.pi / 2.0 - yaw_enu)


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


Q_NED_ENU: Quat = quat_from_rpy(math.pi, 0.0, math.pi / 2.0)
Q_FRD_FLU: Quat = quat_from_rpy(math.pi, 0.0, 0.0)


def attitude_ned_frd_to_enu_flu(q_ned_frd: Quat) -> Quat:
    """An attitude (body FRD in local NED) as body FLU in local ENU, exactly as MAVROS.

    The sign is chosen so that ``w >= 0`` (q and -q are the same rotation).
    """
    q = quat_normalize(quat_multiply(quat_multiply(Q_NED_ENU, q_ned_frd), Q_FRD_FLU))
    return q if q[3] >= 0.0 else (-q[0], -q[1], -q[2], -q[3])


def mavlink_quat(q1: float, q2: float, q3: float, q4: float) -> Quat:
    """MAVLink's (w, x, y, z) quaternion fields (ATTITUDE_QUATERNION q1..q4) as (x, y, z, w)."""
    return (q2, q3, q4, q1)


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


def heading_flu_to_enu(vx_forward: float, vy_left: float, yaw_enu: float) -> tuple[float, float]:
    """A horizontal body (FLU, heading frame) velocity as local ENU (east, north) at ``yaw_enu``.

    Only the heading is used (as PX4 does for BODY_NED): roll and pitch are ignored, so
    "forward" is the horizontal direction the nose points to.
    """
    c, s = math.cos(yaw_enu), math.sin(yaw_enu)
    return (vx_forward * c - vy_left * s, vx_forward * s + vy_left * c)
