"""PositionTarget -> SET_POSITION_TARGET_LOCAL_NED: frames, masks, validation, both autopilots."""

from __future__ import annotations

import math

import msgspec
import pytest
from pymavlink.dialects.v20 import common as mavlink2
from targets import mixed, position, velocity

from dronewrapper.msgs.geometry import Point
from dronewrapper.msgs.mavros import (
    FRAME_BODY_NED,
    FRAME_BODY_OFFSET_NED,
    FRAME_LOCAL_NED,
    MASK_MIXED,
    MASK_POSITION,
    MASK_VELOCITY,
    PositionTarget,
)
from dronewrapper_bridge_mavlink.setpoints import (
    Kind,
    Limits,
    SetpointError,
    hold_target,
    to_local_ned,
    validate,
)

PX4, ARDU = "px4", "ardupilotmega"


def test_body_forward_at_yaw_90_enu_goes_north():
    out = to_local_ned(velocity(vx=1.0), autopilot=PX4, yaw_enu=math.pi / 2, z_enu=0.0)
    assert out.coordinate_frame == FRAME_LOCAL_NED and out.type_mask == MASK_VELOCITY
    assert math.isclose(out.vx, 1.0) and abs(out.vy) < 1e-12  # NED x = north


def test_body_left_at_yaw_0_is_north_and_up_is_negative_down():
    out = to_local_ned(
        velocity(vy=1.0, vz=0.5, yaw_rate=0.3), autopilot=PX4, yaw_enu=0.0, z_enu=0.0
    )
    assert math.isclose(out.vx, 1.0) and abs(out.vy) < 1e-12
    assert math.isclose(out.vz, -0.5)
    assert math.isclose(out.yaw_rate, -0.3)  # CCW (ENU) -> CW (NED)


def test_forward_means_forward_on_every_autopilot():
    for autopilot in (PX4, ARDU):
        out = to_local_ned(velocity(vx=2.0), autopilot=autopilot, yaw_enu=0.0, z_enu=3.0)
        assert out.coordinate_frame == FRAME_LOCAL_NED  # never 8 or 9
        assert math.isclose(out.vy, 2.0) and abs(out.vx) < 1e-12  # facing east: NED y


def test_local_enu_velocity_is_not_rotated():
    out = to_local_ned(velocity(vx=1.0, frame=FRAME_LOCAL_NED), autopilot=PX4, yaw_enu=1.0, z_enu=0)
    assert math.isclose(out.vy, 1.0) and abs(out.vx) < 1e-12  # ENU x east -> NED y


def test_position_enu_to_ned_with_yaw():
    out = to_local_ned(position(1.0, 2.0, 3.0, yaw=0.0), autopilot=PX4, yaw_enu=0.7, z_enu=0.0)
    assert (out.x, out.y, out.z) == (2.0, 1.0, -3.0)
    assert out.type_mask == MASK_POSITION
    assert math.isclose(out.yaw, math.pi / 2)  # ENU yaw 0 (east) = NED yaw +90 deg


def test_mixed_px4_native_altitude():
    out = to_local_ned(mixed(vx=1.0, z=4.0), autopilot=PX4, yaw_enu=math.pi / 2, z_enu=1.0)
    assert out.type_mask == MASK_MIXED
    assert math.isclose(out.z, -4.0) and math.isclose(out.vx, 1.0)


def test_mixed_ardupilot_emulated_with_climb_rate():
    """ArduCopter ignores a partial position: the bridge turns the altitude into vz."""
    out = to_local_ned(mixed(vx=1.0, z=4.0), autopilot=ARDU, yaw_enu=math.pi / 2, z_enu=3.5)
    assert out.type_mask == MASK_VELOCITY
    assert math.isclose(out.vz, -0.5)  # 0.5 m low -> climb 0.5 m/s (NED down negative)
    assert math.isclose(out.vx, 1.0)
    far = to_local_ned(mixed(z=50.0), autopilot=ARDU, yaw_enu=0.0, z_enu=0.0)
    assert math.isclose(far.vz, -Limits().mixed_max_climb)


@pytest.mark.parametrize(
    ("target", "reason"),
    [
        (velocity(vx=math.nan), "finite"),
        (velocity(vz=math.inf), "finite"),
        (velocity(vx=50.0), "horizontal speed"),
        (velocity(vz=-30.0), "vertical speed"),
        (velocity(yaw_rate=20.0), "yaw_rate"),
        (position(x=1e6), "farther"),
        (position(z=-5000.0), "altitude"),
        (position(yaw=math.nan), "finite"),
        (mixed(z=math.nan), "finite"),
        (PositionTarget(type_mask=2040, coordinate_frame=1), "type_mask 2040"),
        (velocity(frame=FRAME_BODY_OFFSET_NED), "coordinate_frame 9"),
        (PositionTarget(type_mask=MASK_POSITION, coordinate_frame=FRAME_BODY_NED), "frame 8"),
    ],
)
def test_bad_setpoints_refused_with_reason(target, reason):
    with pytest.raises(SetpointError, match=reason):
        validate(target)


def test_unused_fields_may_be_nan():
    target = msgspec.structs.replace(velocity(vx=1.0), position=Point(x=math.nan), yaw=math.inf)
    assert validate(target) is Kind.VELOCITY


@pytest.mark.parametrize("mask", [MASK_POSITION, MASK_MIXED])
def test_a_target_that_leaves_out_its_position_is_refused(mask):
    """Left out, the position is UNSET, never the origin at z = 0 (a dive to the ground)."""
    frame = FRAME_LOCAL_NED if mask == MASK_POSITION else FRAME_BODY_NED
    decoded = msgspec.msgpack.decode(
        msgspec.msgpack.encode({"coordinate_frame": frame, "type_mask": mask}), type=PositionTarget
    )
    assert decoded.position is msgspec.UNSET
    with pytest.raises(SetpointError, match=f"position is required with type_mask {mask}"):
        validate(decoded)


def test_hold_target_is_a_position_control():
    target = hold_target((1.0, 2.0, 3.0), 0.5)
    assert validate(target) is Kind.POSITION
    assert (target.position.x, target.position.y, target.position.z, target.yaw) == (1, 2, 3, 0.5)


def test_converted_fields_encode_as_mavlink_bytes():
    """What the bridge sends survives a MAVLink 2 round trip (frame 1, mask kept)."""
    out = to_local_ned(velocity(vx=1.0, yaw_rate=0.2), autopilot=ARDU, yaw_enu=0.3, z_enu=0.0)
    mav = mavlink2.MAVLink(None, srcSystem=255, srcComponent=190)
    msg = mav.set_position_target_local_ned_encode(
        0, 1, 1, out.coordinate_frame, out.type_mask, out.x, out.y, out.z,
        out.vx, out.vy, out.vz, 0, 0, 0, out.yaw, out.yaw_rate,
    )  # fmt: skip
    parsed = mavlink2.MAVLink(None).parse_char(msg.pack(mav))
    assert parsed.coordinate_frame == 1 and parsed.type_mask == MASK_VELOCITY
    assert math.isclose(parsed.vx, math.sin(0.3), rel_tol=1e-6)  # north part of forward
    assert math.isclose(parsed.vy, math.cos(0.3), rel_tol=1e-6)
