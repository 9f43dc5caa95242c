"""Frame helpers for the Tello: its aircraft angles (degrees) <-> ENU/FLU quaternions.

Quaternions are (x, y, z, w) tuples, Hamilton convention like ROS. Angles in radians unless a
name says ``_deg``. The frame-free maths is :mod:`dronewrapper.rotations`, re-exported here.

The Tello reports aircraft Euler angles as MAVLink/NED does: roll positive right side down,
pitch positive nose up, yaw positive clockwise seen from above, 0 at its reference heading
(the heading at power-on: a Tello has no compass). The local ENU frame (``odom``) is fixed at the
take-off point with its x axis along ``reference_yaw`` (ENU yaw of the power-on heading, default
0: x along the power-on heading, as ROS odometry starts), so ``yaw_enu = reference_yaw - yaw``;
roll stays and pitch changes sign (FRD -> FLU), as MAVROS converts.
"""

from __future__ import annotations

import math

from dronewrapper.rotations import (
    Quat,
    Vec3,
    quat_from_rpy,
    rotate,
    rotate_inverse,
    rpy_from_quat,
    wrap_pi,
)


def yaw_tello_to_enu(yaw_deg: float, reference_yaw: float = 0.0) -> float:
    """The Tello's yaw (degrees, clockwise from its reference heading) as ENU yaw (rad, CCW);
    ``reference_yaw`` is the ENU yaw of the reference heading (rad)."""
    return wrap_pi(reference_yaw - math.radians(yaw_deg))


def attitude_enu(
    roll_deg: float, pitch_deg: float, yaw_deg: float, reference_yaw: float = 0.0
) -> Quat:
    """The Tello's attitude angles (degrees, FRD convention) as body FLU in local ENU."""
    return quat_from_rpy(
        math.radians(roll_deg),
        -math.radians(pitch_deg),
        yaw_tello_to_enu(yaw_deg, reference_yaw),
    )


def enu_to_heading_flu(east: float, north: float, yaw_enu: float) -> tuple[float, float]:
    """A horizontal ENU vector as (forward, left) of a body at heading ``yaw_enu`` (level)."""
    c, s = math.cos(yaw_enu), math.sin(yaw_enu)
    return (c * east + s * north, -s * east + c * north)


__all__ = [
    "Quat",
    "Vec3",
    "attitude_enu",
    "enu_to_heading_flu",
    "quat_from_rpy",
    "rotate",
    "rotate_inverse",
    "rpy_from_quat",
    "wrap_pi",
    "yaw_tello_to_enu",
]
