"""Frame conversions ENU/FLU <-> NED/FRD, quaternions and geodetic offsets."""

from __future__ import annotations

import math

import pytest

from dronewrapper.rotations import quat_from_rpy
from dronewrapper_sim import frames
from dronewrapper_sim.battery import Battery, motor_current
from dronewrapper_sim.dynamics import GRAVITY


def test_enu_ned_round_trip_and_axes():
    assert frames.enu_to_ned(1.0, 2.0, 3.0) == (2.0, 1.0, -3.0)
    assert frames.ned_to_enu(*frames.enu_to_ned(1.0, 2.0, 3.0)) == (1.0, 2.0, 3.0)


@pytest.mark.parametrize(
    ("yaw_enu", "yaw_ned"),
    [(0.0, math.pi / 2), (math.pi / 2, 0.0), (math.pi, -math.pi / 2), (-math.pi / 2, -math.pi)],
)
def test_yaw_conventions(yaw_enu, yaw_ned):
    """ENU yaw 0 = facing east = NED yaw 90 deg; facing north is 0 in NED."""
    assert frames.wrap_pi(frames.yaw_enu_to_ned(yaw_enu) - yaw_ned) == pytest.approx(0.0)
    back = frames.yaw_ned_to_enu(frames.yaw_enu_to_ned(yaw_enu))
    assert frames.wrap_pi(back - yaw_enu) == pytest.approx(0.0, abs=1e-12)


def test_euler_flu_to_frd_signs():
    roll, pitch, yaw = frames.euler_flu_enu_to_frd_ned(0.1, 0.2, 0.0)
    assert roll == 0.1
    assert pitch == -0.2  # FLU pitch nose-down positive = FRD pitch negative
    assert yaw == pytest.approx(math.pi / 2)
    assert frames.rates_flu_to_frd(1.0, 2.0, 3.0) == (1.0, -2.0, -3.0)


def test_quaternion_of_a_yaw_and_the_thrust_axis():
    x, y, z, w = quat_from_rpy(0.0, 0.0, math.pi / 2)
    assert (x, y) == (0.0, 0.0)
    assert z == pytest.approx(math.sqrt(0.5))
    assert w == pytest.approx(math.sqrt(0.5))
    # nose down (FLU pitch > 0) while facing north tilts the thrust to the north
    ux, uy, uz = frames.body_up_enu(0.0, 0.3, math.pi / 2)
    assert uy == pytest.approx(math.sin(0.3))
    assert ux == pytest.approx(0.0, abs=1e-12)
    assert uz == pytest.approx(math.cos(0.3))


def test_geodetic_offsets_round_trip_and_scale():
    lat0, lon0 = 47.397742, 8.545594
    lat, lon = frames.offset_to_geodetic(100.0, -50.0, lat0, lon0)
    assert lat > lat0 and lon < lon0
    assert (lat - lat0) * 111_195 == pytest.approx(100.0, rel=1e-3)
    north, east = frames.geodetic_to_offset(lat, lon, lat0, lon0)
    assert north == pytest.approx(100.0, abs=1e-6)
    assert east == pytest.approx(-50.0, abs=1e-6)


def test_battery_drains_and_sags_under_load():
    battery = Battery(cells=4, capacity_mah=5000.0)
    full = battery.voltage
    assert 16.5 < full <= 16.8
    hover = motor_current(True, GRAVITY)
    assert 15.0 < hover < 25.0
    assert motor_current(False, 0.0) < 1.0
    for _ in range(600):  # 10 minutes of hover
        battery.step(hover, 1.0)
    assert 0.2 < battery.remaining < 0.6
    assert battery.voltage < full
    loaded = battery.voltage
    battery.step(0.0, 0.001)
    assert battery.voltage > loaded  # no load, no sag
