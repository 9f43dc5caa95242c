"""The one rotation module the bridges, the SDK and the simulator share."""

from __future__ import annotations

import math

import pytest

from dronewrapper.msgs.geometry import Quaternion
from dronewrapper.rotations import (
    quat_from_rpy,
    quat_multiply,
    rotate,
    rotate_inverse,
    rpy_from_quat,
    wrap_pi,
)
from dronewrapper.telemetry import euler_from_quaternion


@pytest.mark.parametrize("angle", [-7.0, -math.pi, 0.0, 3.0, math.pi, 10.0])
def test_wrap_pi_lands_in_minus_pi_to_pi(angle: float):
    wrapped = wrap_pi(angle)
    assert -math.pi <= wrapped < math.pi
    assert math.isclose(math.cos(wrapped), math.cos(angle), abs_tol=1e-12)


@pytest.mark.parametrize("rpy", [(0.1, -0.2, 0.3), (0.0, 0.0, -3.0), (-0.5, 0.4, 2.5)])
def test_euler_angles_round_trip_and_the_sdk_reads_them_alike(rpy):
    q = quat_from_rpy(*rpy)
    assert rpy_from_quat(q) == pytest.approx(rpy, abs=1e-12)
    x, y, z, w = q
    assert euler_from_quaternion(Quaternion(x=x, y=y, z=z, w=w)) == pytest.approx(rpy, abs=1e-12)


def test_a_yaw_turns_forward_into_left_and_back():
    q = quat_from_rpy(0.0, 0.0, math.pi / 2)
    assert rotate(q, (1.0, 0.0, 0.0)) == pytest.approx((0.0, 1.0, 0.0), abs=1e-12)
    assert rotate_inverse(q, (0.0, 1.0, 0.0)) == pytest.approx((1.0, 0.0, 0.0), abs=1e-12)
    half = quat_from_rpy(0.0, 0.0, math.pi / 4)
    assert quat_multiply(half, half) == pytest.approx(q, abs=1e-12)
