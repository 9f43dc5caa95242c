"""PX4's uORB values as the bridge's messages and back: frames (NED/FRD <-> ENU/FLU), modes, the
offboard setpoints for the three controls, and vehicle commands."""

from __future__ import annotations

import math

import pytest

from dronewrapper.msgs.geometry import Point, Vector3
from dronewrapper.msgs.mavros import (
    FRAME_BODY_NED,
    FRAME_LOCAL_NED,
    LANDED_STATE_IN_AIR,
    LANDED_STATE_ON_GROUND,
    MASK_MIXED,
    MASK_POSITION,
    MASK_VELOCITY,
    PositionTarget,
)
from dronewrapper_bridge_base.odometry import Headers
from dronewrapper_bridge_base.setpoint_limits import Kind
from dronewrapper_bridge_px4_zenoh import commands, modes, telemetry, trajectory

LEVEL_NORTH = {"q": [1.0, 0.0, 0.0, 0.0]}  # body FRD aligned with NED: nose north


def position(**fields):
    base = {"xy_valid": True, "z_valid": True, "v_xy_valid": True, "v_z_valid": True}
    base.update({"x": 1.0, "y": 2.0, "z": -3.0, "vx": 0.5, "vy": -0.25, "vz": -1.0})
    base.update(fields)
    return base


def test_pose_and_velocity_are_enu_and_the_nose_north_is_yaw_90_degrees():
    q = telemetry.attitude_enu_flu(LEVEL_NORTH)
    enu, velocity = telemetry.local_position(position()), telemetry.local_velocity(position())
    pose, velocities = telemetry.local_odometry(Headers(), enu, q, velocity, 12.5)
    assert (pose.pose.position.x, pose.pose.position.y, pose.pose.position.z) == (2.0, 1.0, 3.0)
    o = pose.pose.orientation
    assert math.isclose(2 * math.atan2(o.z, o.w), math.pi / 2, abs_tol=1e-9)
    assert pose.header.stamp == 12.5 and pose.header.frame_id == "map"
    local, body = velocities
    v = local.twist.linear
    assert (v.x, v.y, v.z) == (-0.25, 0.5, 1.0) and local.header.frame_id == "map"
    assert body.twist.linear.x == pytest.approx(0.5) and body.twist.linear.y == pytest.approx(0.25)
    assert body.header.frame_id == "base_link"  # forward, left


def test_invalid_estimates_publish_nothing():
    q = telemetry.attitude_enu_flu(LEVEL_NORTH)
    assert telemetry.local_position(position(xy_valid=False)) is None
    assert telemetry.local_velocity(position(v_z_valid=False)) is None
    _, velocities = telemetry.local_odometry(Headers(), (0.0, 0.0, 0.0), q, None, 0.0)
    assert velocities is None  # the pose alone while the velocity is not valid
    assert telemetry.attitude_enu_flu({"q": [math.nan, 0.0, 0.0, 0.0]}) is None


def test_state_modes_and_landed_state():
    status = {"nav_state": 14, "arming_state": 2}
    state = telemetry.state(status, connected=True, failsafe="", commander="alice")
    assert (state.mode, state.armed, state.guided, state.autopilot) == (
        "OFFBOARD",
        True,
        True,
        "px4",
    )
    assert state.commander == "alice" and not state.manual_input
    hold = telemetry.state(
        {"nav_state": 4, "arming_state": 1}, connected=True, failsafe="hold", commander=""
    )
    assert (hold.mode, hold.armed, hold.guided, hold.failsafe) == (
        "AUTO.LOITER",
        False,
        False,
        "hold",
    )
    assert telemetry.extended_state({"landed": True}, 0.0).landed_state == LANDED_STATE_ON_GROUND
    assert telemetry.extended_state({"landed": False}, 0.0).landed_state == LANDED_STATE_IN_AIR


def test_mode_names_round_trip_and_an_unknown_mode_lists_the_known_ones():
    for name, nav_state in modes.NAV_STATE_OF_MODE.items():
        assert modes.mode_name(nav_state) == name
        assert modes.nav_state_of(name.lower()) == nav_state
    assert modes.mode_name(12) == "AUTO.LAND"  # DESCEND, as PX4's MAVLink shows it
    assert modes.mode_name(25) == "EXTERNAL3"
    assert modes.mode_name(99) == "NAV_STATE_99"
    with pytest.raises(ValueError, match="OFFBOARD"):
        modes.nav_state_of("GUIDED")


def test_battery_and_global_position():
    battery = telemetry.battery(
        {"voltage_v": 15.8, "current_a": 12.0, "remaining": 0.8, "connected": True}, 1.0
    )
    assert (battery.voltage, battery.percentage, battery.present) == (15.8, 0.8, True)
    fix = telemetry.global_position(
        {"lat": 47.39, "lon": 8.54, "alt": 488.5, "lat_lon_valid": True, "alt_valid": True}, 1.0
    )
    assert (fix.latitude, fix.longitude, fix.altitude, fix.status.status) == (47.39, 8.54, 488.5, 0)
    nofix = telemetry.global_position(
        {"lat": 0.0, "lon": 0.0, "alt": 0.0, "lat_lon_valid": False, "alt_valid": True}, 1.0
    )
    assert nofix.status.status == -1


def _nan_or(values):
    return [None if math.isnan(v) else v for v in values]


def test_position_target_is_a_ned_position_and_yaw():
    target = PositionTarget(
        coordinate_frame=FRAME_LOCAL_NED,
        type_mask=MASK_POSITION,
        position=Point(x=1, y=2, z=3),
        yaw=0.0,
    )
    sp = trajectory.trajectory_setpoint(target, Kind.POSITION, yaw_enu=1.0)
    assert sp["position"] == [2.0, 1.0, -3.0]
    assert sp["yaw"] == pytest.approx(math.pi / 2)  # facing east
    assert _nan_or(sp["velocity"]) == [None, None, None] and math.isnan(sp["yawspeed"])
    mode = trajectory.control_mode(Kind.POSITION)
    assert mode["position"] and not mode["velocity"] and not mode["attitude"]


def test_body_velocity_is_rotated_by_the_heading_and_yaw_rate_changes_sign():
    target = PositionTarget(
        coordinate_frame=FRAME_BODY_NED,
        type_mask=MASK_VELOCITY,
        velocity=Vector3(x=1.0, z=0.5),
        yaw_rate=0.3,
    )
    sp = trajectory.trajectory_setpoint(target, Kind.VELOCITY, yaw_enu=math.pi / 2)  # nose north
    assert sp["velocity"] == pytest.approx([1.0, 0.0, -0.5])
    assert sp["yawspeed"] == pytest.approx(-0.3)
    assert _nan_or(sp["position"]) == [None, None, None]
    assert trajectory.control_mode(Kind.VELOCITY)["velocity"]


def test_mixed_target_holds_the_altitude_and_leaves_vertical_speed_free():
    target = PositionTarget(
        coordinate_frame=FRAME_BODY_NED,
        type_mask=MASK_MIXED,
        velocity=Vector3(x=1.0),
        position=Point(x=0, y=0, z=4.0),
    )
    sp = trajectory.trajectory_setpoint(target, Kind.MIXED, yaw_enu=0.0)  # nose east
    assert _nan_or(sp["position"]) == [None, None, -4.0]
    assert _nan_or(sp["velocity"]) == [pytest.approx(0.0), 1.0, None]
    mode = trajectory.control_mode(Kind.MIXED)
    assert mode["position"] and mode["velocity"]


def test_vehicle_commands():
    arm = commands.arm(True)
    assert (arm["command"], arm["param1"], arm["from_external"]) == (400, 1.0, True)
    assert math.isnan(arm["param7"]) and arm["target_system"] == 1
    offboard = commands.set_nav_state(modes.nav_state_of("OFFBOARD"), target_system=2)
    assert (offboard["command"], offboard["param1"], offboard["target_system"]) == (100001, 14.0, 2)
    assert commands.result_text(commands.DENIED) == "denied"
    assert commands.result_text(42) == "result 42"
    with pytest.raises(ValueError):
        commands.vehicle_command(22, *range(8))
