"""Tello state strings -> numbers -> MAVROS-shaped messages (ENU/FLU), dead reckoning."""

from __future__ import annotations

import math

import pytest

from dronewrapper.msgs.mavros import (
    LANDED_STATE_IN_AIR,
    LANDED_STATE_LANDING,
    LANDED_STATE_ON_GROUND,
    LANDED_STATE_TAKEOFF,
)
from dronewrapper_bridge_tello.frames import attitude_enu, rotate, rpy_from_quat
from dronewrapper_bridge_tello.state import StateError, parse_state
from dronewrapper_bridge_tello.telemetry import LandedTracker, Telemetry


def state_string(**over) -> bytes:
    """A state string in the real field order (SDK 2.0), with fields overridden."""
    fields = {
        "mid": "-1", "x": "0", "y": "0", "z": "0", "mpry": "0,0,0",
        "pitch": "0", "roll": "0", "yaw": "0", "vgx": "0", "vgy": "0", "vgz": "0",
        "templ": "60", "temph": "62", "tof": "10", "h": "0", "bat": "87",
        "baro": "120.52", "time": "0", "agx": "-1.00", "agy": "0.00", "agz": "-999.00",
    }  # fmt: skip
    fields.update({k: str(v) for k, v in over.items()})
    return ("".join(f"{k}:{v};" for k, v in fields.items()) + "\r\n").encode()


def test_real_state_string_parses_in_drone_units():
    s = parse_state(state_string(pitch=-3, roll=2, yaw=-45, vgx=5, vgy=-2, vgz=1, h=80, tof=92))
    assert (s.pitch_deg, s.roll_deg, s.yaw_deg) == (-3.0, 2.0, -45.0)
    assert (s.vgx, s.vgy, s.vgz) == (5.0, -2.0, 1.0)
    assert (s.h_cm, s.tof_cm, s.battery_percent, s.baro_m) == (80.0, 92.0, 87.0, 120.52)


@pytest.mark.parametrize(
    "datagram",
    [
        b"",
        b"\xff\xfe\x00garbage",
        b"ok",
        b"pitch:0;roll:0;",  # fields missing
        state_string(yaw="nan"),
        state_string(vgx="fast"),
        state_string(bat=150),
        state_string(h="inf"),
        b"x" * 5000,
        b"pitch0;roll:0",
    ],
)
def test_malformed_state_strings_are_refused_with_a_reason(datagram):
    with pytest.raises(StateError):
        parse_state(datagram)


def test_optional_field_garbage_does_not_reject_the_string():
    assert math.isnan(parse_state(state_string(baro="??")).baro_m)


def test_attitude_quaternion_is_enu_flu_with_ccw_yaw():
    # Tello yaw 0 (its power-on heading) is the local frame's +x: ENU yaw 0
    assert rpy_from_quat(attitude_enu(0, 0, 0))[2] == pytest.approx(0.0)
    # clockwise 90 degrees (Tello yaw +90) -> ENU yaw -90 degrees (CCW positive)
    assert rpy_from_quat(attitude_enu(0, 0, 90))[2] == pytest.approx(-math.pi / 2)
    assert rpy_from_quat(attitude_enu(0, 0, -30))[2] == pytest.approx(math.radians(30))
    # a known reference heading: power-on heading north (ENU yaw 90), turned 90 cw -> east
    assert rpy_from_quat(attitude_enu(0, 0, 90, math.pi / 2))[2] == pytest.approx(0.0, abs=1e-9)
    # nose up (Tello pitch +10) -> the body x axis points up in ENU
    nose = rotate(attitude_enu(0, 10, 90), (1.0, 0.0, 0.0))
    assert nose[2] == pytest.approx(math.sin(math.radians(10)))
    # right side down (roll +10) -> the body's left axis (FLU y) points up
    left = rotate(attitude_enu(10, 0, 90), (0.0, 1.0, 0.0))
    assert left[2] == pytest.approx(math.sin(math.radians(10)))
    q = attitude_enu(4, -7, 33)
    assert math.isclose(sum(c * c for c in q), 1.0)


def feed(t: Telemetry, now: float, **over) -> None:
    t.on_state(parse_state(state_string(**over)), now)


def test_velocities_in_metres_per_second_enu_and_flu():
    t = Telemetry()
    # turned 90 deg clockwise (facing -y), moving along the power-on heading at 5 dm/s, climbing
    feed(t, 0.0, yaw=90, vgx=5, vgy=0, vgz=-2)
    _, local, body = t.messages(1.0)
    assert (local.twist.linear.x, local.twist.linear.y) == pytest.approx((0.5, 0.0))
    assert local.twist.linear.z == pytest.approx(0.2)  # vgz is down-positive
    # the power-on heading (+x) is to the left of a drone facing -y
    assert body.twist.linear.x == pytest.approx(0.0, abs=1e-9)
    assert body.twist.linear.y == pytest.approx(0.5)
    assert body.twist.linear.z == pytest.approx(0.2)
    feed(t, 0.1, yaw=0, vgy=3)  # vgy > 0 is to the right of the power-on heading: -y
    _, local, body = t.messages(1.0)
    assert (local.twist.linear.x, local.twist.linear.y) == pytest.approx((0.0, -0.3))
    assert body.twist.linear.y == pytest.approx(-0.3)


def test_reference_yaw_turns_the_local_frame():
    t = Telemetry(reference_yaw=math.pi / 2)  # powered on facing north
    feed(t, 0.0, yaw=0, vgx=5)
    _, local, _ = t.messages(1.0)
    assert (local.twist.linear.x, local.twist.linear.y) == pytest.approx((0.0, 0.5))


def test_body_frd_velocity_frame():
    t = Telemetry(velocity_frame="body_frd")
    feed(t, 0.0, yaw=-90, vgx=5, vgy=3)  # forward 0.5, right 0.3, facing +y
    _, local, body = t.messages(1.0)
    assert (body.twist.linear.x, body.twist.linear.y) == pytest.approx((0.5, -0.3))
    assert (local.twist.linear.x, local.twist.linear.y) == pytest.approx((0.3, 0.5))


def test_position_is_dead_reckoned_and_reset_on_takeoff():
    t = Telemetry()
    for i in range(11):  # 1 s at 10 Hz, 1 m/s along the power-on heading, 80 cm high
        feed(t, i * 0.1, vgx=10, h=80)
    pose, _, _ = t.messages(5.0)
    assert pose.header.frame_id == "odom"
    assert pose.pose.position.x == pytest.approx(1.0)
    assert pose.pose.position.y == pytest.approx(0.0)
    assert pose.pose.position.z == pytest.approx(0.8)
    feed(t, 3.0, vgx=10, h=80)  # a 2 s gap is not integrated over
    assert t.position_enu[0] == pytest.approx(1.0)
    t.reset_position()
    assert t.position_enu[:2] == (0.0, 0.0)


def test_height_from_tof_minus_its_ground_reading():
    t = Telemetry(height_source="tof", tof_ground_cm=10)
    feed(t, 0.0, tof=135, h=120)
    assert t.position_enu[2] == pytest.approx(1.25)


def test_battery_is_a_fraction_with_unknown_voltage():
    t = Telemetry()
    feed(t, 0.0, bat=42)
    b = t.battery_message(1.0)
    assert b.percentage == pytest.approx(0.42) and math.isnan(b.voltage)


def test_yaw_rate_from_successive_headings_ccw_positive():
    t = Telemetry()
    feed(t, 0.0, yaw=10)
    feed(t, 0.1, yaw=7)  # turned 3 degrees counter-clockwise in 0.1 s
    _, local, body = t.messages(1.0)
    assert body.twist.angular.z == pytest.approx(math.radians(30))
    assert local.twist.angular.z == body.twist.angular.z
    feed(t, 0.2, yaw=179)
    feed(t, 0.3, yaw=-179)  # across +-180: 2 degrees clockwise
    assert t.messages(1.0)[2].twist.angular.z == pytest.approx(-math.radians(20))


def test_landed_state_from_commands_and_motion():
    lt = LandedTracker()
    assert lt.state == LANDED_STATE_ON_GROUND and not lt.flying
    lt.on_takeoff_sent()
    assert lt.state == LANDED_STATE_TAKEOFF and lt.flying
    lt.on_takeoff_done(True)
    assert lt.state == LANDED_STATE_IN_AIR
    for i in range(5):
        lt.on_state(90, float(i), float(i))
    lt.on_land_sent()
    assert lt.state == LANDED_STATE_LANDING
    lt.on_land_done(True)
    assert lt.state == LANDED_STATE_ON_GROUND


def test_auto_land_and_second_client_takeoff_seen_from_motion():
    lt = LandedTracker()
    for i in range(4):  # someone else took off: motors tick, height 80 cm
        lt.on_state(80 if i > 1 else 0, float(i), float(i))
    assert lt.state == LANDED_STATE_IN_AIR
    lt.on_state(0, 4.0, 4.0)  # on the ground but motors still ticked 0 s ago
    assert lt.state == LANDED_STATE_IN_AIR
    lt.on_state(0, 4.0, 7.0)  # no motor tick for 3 s at 0 cm
    assert lt.state == LANDED_STATE_ON_GROUND


def test_refused_takeoff_goes_back_to_the_ground():
    lt = LandedTracker()
    lt.on_takeoff_sent()
    lt.on_takeoff_done(False)
    assert lt.state == LANDED_STATE_ON_GROUND
