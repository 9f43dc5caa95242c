"""Frame conversions between an autopilot's NED / FRD and DroneWrapper's ENU / FLU, as MAVROS does
(MAVLink and PX4's uORB use the same frames).

Local frames: NED (x north, y east, z down) <-> ENU (x east, y north, z up).
Body frames: FRD (forward, right, down) <-> FLU (forward, left, up).
Quaternions are (x, y, z, w) tuples, Hamilton convention like ROS. Angles in radians. The
frame-free maths (quaternions, Euler angles, wrapping) is :mod:`dronewrapper.rotations`,
re-exported here.

The orientation conversion is MAVROS's ``ftf::transform_orientation_ned_enu`` followed by
``transform_orientation_aircraft_baselink``: ``q_enu_flu = Q_NED_ENU * q_ned_frd * Q_FRD_FLU``
with ``Q_NED_ENU = rpy(pi, 0, pi/2)`` and ``Q_FRD_FLU = rpy(pi, 0, 0)``. In Euler terms:
roll stays, pitch and yaw-rate change sign, yaw_enu = pi/2 - yaw_ned.
"""

from __future__ import annotations

import math

from dronewrapper.rotations import (
    Quat,
    Vec3,
    quat_from_rpy,
    quat_multiply,
    quat_normalize,
    rotate,
    rotate_inverse,
    rpy_from_quat,
    wrap_pi,
)


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


def yaw_ned_to_enu(yaw_ned: float) -> float:
    """Heading clockwise from north (NED) -> counter-clockwise from east (ENU), wrapped."""
    return wrap_pi(math.pi / 2.0 - yaw_ned)


def yaw_enu_to_ned(yaw_enu: float) -> float:
    """Heading counter-clockwise from east (ENU) -> clockwise from north (NED), wrapped."""
    return wrap_pi(math.pi / 2.0 - yaw_enu)


Q_NED_ENU: Quat = quat_from_rpy(math.pi, 0.0, math.pi / 2.0)
Q_FRD_FLU: Quat = quat_from_rpy(math.pi, 0.0, 0.0)


def attitude_ned_frd_to_enu_flu(q_ned_frd: Quat) -> Quat:
    """An attitude (body FRD in local NED) as body FLU in local ENU, exactly as MAVROS.

    The sign is chosen so that ``w >= 0`` (q and -q are the same rotation).
    """
    q = quat_normalize(quat_multiply(quat_multiply(Q_NED_ENU, q_ned_frd), Q_FRD_FLU))
    return q if q[3] >= 0.0 else (-q[0], -q[1], -q[2], -q[3])


def heading_flu_to_enu(vx_forward: float, vy_left: float, yaw_enu: float) -> tuple[float, float]:
    """A horizontal body (FLU, heading frame) velocity as local ENU (east, north) at ``yaw_enu``.

    Only the heading is used (as PX4 does for BODY_NED): roll and pitch are ignored, so
    "forward" is the horizontal direction the nose points to.
    """
    c, s = math.cos(yaw_enu), math.sin(yaw_enu)
    return (vx_forward * c - vy_left * s, vx_forward * s + vy_left * c)


__all__ = [
    "Q_FRD_FLU",
    "Q_NED_ENU",
    "Quat",
    "Vec3",
    "attitude_ned_frd_to_enu_flu",
    "enu_to_ned",
    "flu_to_frd",
    "frd_to_flu",
    "heading_flu_to_enu",
    "ned_to_enu",
    "quat_from_rpy",
    "quat_multiply",
    "quat_normalize",
    "rotate",
    "rotate_inverse",
    "rpy_from_quat",
    "wrap_pi",
    "yaw_enu_to_ned",
    "yaw_ned_to_enu",
]
