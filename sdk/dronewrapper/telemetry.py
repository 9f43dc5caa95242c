"""Telemetry messages as the paper's numpy values (pure functions, no I/O).

Frames and units (docs/design.md): local ENU (x east, y north, z up) in metres, fixed at the
take-off point; body FLU (forward, left, up) in m/s; angles in radians, yaw counter-clockwise
positive from east.
"""

from __future__ import annotations

import numpy as np

from dronewrapper.msgs.geometry import PoseStamped, Quaternion, TwistStamped
from dronewrapper.msgs.sensor import NavSatFix
from dronewrapper.rotations import rpy_from_quat


def euler_from_quaternion(q: Quaternion) -> tuple[float, float, float]:
    """(roll, pitch, yaw) in radians of a unit quaternion, ZYX (yaw-pitch-roll) convention.

    Pitch is clamped to +-pi/2 when the quaternion is not exactly unit length.
    """
    return rpy_from_quat((q.x, q.y, q.z, q.w))


def position_of(msg: PoseStamped) -> np.ndarray:
    """``np.array([x, y, z])``: position in local ENU metres."""
    p = msg.pose.position
    return np.array([p.x, p.y, p.z])


def orientation_of(msg: PoseStamped) -> np.ndarray:
    """``np.array([roll, pitch, yaw])`` in radians (ENU; yaw 0 = facing east, CCW +)."""
    return np.array(euler_from_quaternion(msg.pose.orientation))


def linear_of(msg: TwistStamped) -> np.ndarray:
    """``np.array([vx, vy, vz])``: linear velocity in m/s, in the message's frame."""
    v = msg.twist.linear
    return np.array([v.x, v.y, v.z])


def yaw_rate_of(msg: TwistStamped) -> float:
    """Yaw rate in rad/s (counter-clockwise positive) from a body FLU twist."""
    return float(msg.twist.angular.z)


def global_of(msg: NavSatFix) -> np.ndarray:
    """``np.array([latitude, longitude, altitude])``: degrees, degrees, metres AMSL."""
    return np.array([msg.latitude, msg.longitude, msg.altitude])
