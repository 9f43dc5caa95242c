"""Telemetry conversions: quaternion to Euler angles (ENU), message fields to numpy arrays."""

from __future__ import annotations

import math

import numpy as np
import pytest

from dronewrapper.msgs import geometry, sensor
from dronewrapper.telemetry import (
    euler_from_quaternion,
    global_of,
    linear_of,
    orientation_of,
    position_of,
    yaw_rate_of,
)


def quaternion(roll: float, pitch: float, yaw: float) -> geometry.Quaternion:
    cr, sr = math.cos(roll / 2), math.sin(roll / 2)
    cp, sp = math.cos(pitch / 2), math.sin(pitch / 2)
    cy, sy = math.cos(yaw / 2), math.sin(yaw / 2)
    return geometry.Quaternion(
        w=cr * cp * cy + sr * sp * sy,
        x=sr * cp * cy - cr * sp * sy,
        y=cr * sp * cy + sr * cp * sy,
        z=cr * cp * sy - sr * sp * cy,
    )


@pytest.mark.parametrize(
    "angles", [(0.0, 0.0, 0.0), (0.1, -0.2, 1.5), (-0.3, 0.4, -2.8), (0.0, 0.0, math.pi / 2)]
)
def test_euler_round_trip(angles):
    assert euler_from_quaternion(quaternion(*angles)) == pytest.approx(angles, abs=1e-9)


def test_yaw_is_counter_clockwise_from_east():
    # a quarter turn about +z (up): the nose points north, yaw +pi/2
    q = geometry.Quaternion(z=math.sin(math.pi / 4), w=math.cos(math.pi / 4))
    assert euler_from_quaternion(q)[2] == pytest.approx(math.pi / 2)


def test_non_unit_quaternion_does_not_raise():
    _, pitch, _ = euler_from_quaternion(geometry.Quaternion(x=0.0, y=0.8, z=0.0, w=0.8))
    assert math.isfinite(pitch) and abs(pitch) <= math.pi / 2


def test_arrays_from_messages():
    pose = geometry.PoseStamped(
        pose=geometry.Pose(
            position=geometry.Point(x=1.0, y=2.0, z=3.0), orientation=quaternion(0.0, 0.0, 0.7)
        )
    )
    assert isinstance(position_of(pose), np.ndarray)
    assert position_of(pose).tolist() == [1.0, 2.0, 3.0]
    assert orientation_of(pose) == pytest.approx([0.0, 0.0, 0.7])
    twist = geometry.TwistStamped(
        twist=geometry.Twist(
            linear=geometry.Vector3(x=0.5, y=-0.25), angular=geometry.Vector3(z=0.9)
        )
    )
    assert linear_of(twist).tolist() == [0.5, -0.25, 0.0]
    assert yaw_rate_of(twist) == 0.9
    fix = sensor.NavSatFix(latitude=40.3, longitude=-3.7, altitude=650.0)
    assert global_of(fix).tolist() == [40.3, -3.7, 650.0]
