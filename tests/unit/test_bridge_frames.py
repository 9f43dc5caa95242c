"""Frame conversions: ENU<->NED, FLU<->FRD, MAVROS's orientation conversion, heading rotation."""

from __future__ import annotations

import math
import random

import pytest

from dronewrapper_bridge_base import frames


def close(a, b, tol=1e-9):
    return all(abs(x - y) <= tol for x, y in zip(a, b, strict=True))


def same_rotation(q1, q2, tol=1e-9):
    return close(q1, q2, tol) or close(q1, tuple(-c for c in q2), tol)


def test_enu_ned_swap_and_negate():
    assert frames.ned_to_enu((1.0, 2.0, 3.0)) == (2.0, 1.0, -3.0)
    assert frames.enu_to_ned(frames.ned_to_enu((1.0, 2.0, 3.0))) == (1.0, 2.0, 3.0)


def test_flu_frd():
    assert frames.flu_to_frd((1.0, 2.0, 3.0)) == (1.0, -2.0, -3.0)
    assert frames.frd_to_flu(frames.flu_to_frd((4.0, 5.0, 6.0))) == (4.0, 5.0, 6.0)


@pytest.mark.parametrize(
    ("yaw_ned", "yaw_enu"),
    [(0.0, math.pi / 2), (math.pi / 2, 0.0), (math.pi, -math.pi / 2), (-math.pi / 2, -math.pi)],
)
def test_yaw_conversion(yaw_ned, yaw_enu):
    # north (NED yaw 0) is ENU yaw +90 deg; east (NED +90) is ENU 0
    assert math.isclose(
        frames.wrap_pi(frames.yaw_ned_to_enu(yaw_ned) - yaw_enu), 0.0, abs_tol=1e-12
    ) or math.isclose(abs(frames.yaw_ned_to_enu(yaw_ned)), math.pi)
    assert math.isclose(
        math.cos(frames.yaw_enu_to_ned(frames.yaw_ned_to_enu(yaw_ned))), math.cos(yaw_ned)
    )


def test_rpy_quaternion_round_trip():
    rng = random.Random(4)
    for _ in range(200):
        rpy = (rng.uniform(-3, 3), rng.uniform(-1.5, 1.5), rng.uniform(-3, 3))
        back = frames.rpy_from_quat(frames.quat_from_rpy(*rpy))
        assert close(back, rpy, 1e-9)


def test_attitude_conversion_matches_mavros_euler_relation():
    """MAVROS: roll stays, pitch flips sign, yaw_enu = pi/2 - yaw_ned."""
    rng = random.Random(7)
    for _ in range(200):
        roll, pitch, yaw = rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-3, 3)
        q_enu = frames.attitude_ned_frd_to_enu_flu(frames.quat_from_rpy(roll, pitch, yaw))
        expected = frames.quat_from_rpy(roll, -pitch, math.pi / 2 - yaw)
        assert same_rotation(q_enu, expected, 1e-9)
        assert q_enu[3] >= 0.0


def test_level_north_facing_vehicle_points_along_enu_y():
    q = frames.attitude_ned_frd_to_enu_flu(frames.quat_from_rpy(0.0, 0.0, 0.0))  # nose north
    nose = frames.rotate(q, (1.0, 0.0, 0.0))
    assert close(nose, (0.0, 1.0, 0.0), 1e-12)  # ENU +y is north
    up = frames.rotate(q, (0.0, 0.0, 1.0))
    assert close(up, (0.0, 0.0, 1.0), 1e-12)


def test_rotate_inverse_undoes_rotate():
    q = frames.quat_from_rpy(0.3, -0.2, 1.1)
    v = (1.0, -2.0, 0.5)
    assert close(frames.rotate_inverse(q, frames.rotate(q, v)), v, 1e-12)


def test_body_forward_at_yaw_90_goes_north():
    east, north = frames.heading_flu_to_enu(1.0, 0.0, math.pi / 2)
    assert abs(east) < 1e-12 and math.isclose(north, 1.0)
    # body "left" at yaw 0 (facing east) is north
    east, north = frames.heading_flu_to_enu(0.0, 1.0, 0.0)
    assert abs(east) < 1e-12 and math.isclose(north, 1.0)
