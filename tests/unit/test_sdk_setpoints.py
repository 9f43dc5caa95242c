"""Setpoint building: docs/design.md's masks/frames, and argument validation (no I/O)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from dronewrapper.errors import InvalidArgument
from dronewrapper.msgs import PositionTarget, codec
from dronewrapper.msgs.mavros import FRAME_BODY_NED, FRAME_LOCAL_NED
from dronewrapper.setpoints import (
    check_stamp,
    finite,
    mixed_target,
    position_target,
    velocity_target,
)


def test_position_target_matches_design_table():
    msg = position_target(1.0, 2.0, 3.0, 0.5, stamp=100.0)
    assert msg.type_mask == 3064
    assert msg.coordinate_frame == FRAME_LOCAL_NED == 1
    assert (msg.position.x, msg.position.y, msg.position.z) == (1.0, 2.0, 3.0)
    assert msg.yaw == 0.5
    assert msg.header.stamp == 100.0


def test_velocity_target_is_body_flu_with_yaw_rate():
    msg = velocity_target(1.0, -0.5, 0.25, 1.0, stamp=5.0)
    assert msg.type_mask == 1991
    assert msg.coordinate_frame == FRAME_BODY_NED == 8
    # vx stays forward and vy stays left: no x/y swap (a bug of the original)
    assert (msg.velocity.x, msg.velocity.y, msg.velocity.z) == (1.0, -0.5, 0.25)
    assert msg.yaw_rate == 1.0


def test_mixed_target_carries_altitude_in_position_z():
    msg = mixed_target(0.5, 0.1, 2.5, -0.3, stamp=5.0)
    assert msg.type_mask == 1987
    assert msg.coordinate_frame == 8
    assert msg.position.z == 2.5
    assert (msg.velocity.x, msg.velocity.y, msg.velocity.z) == (0.5, 0.1, 0.0)
    assert msg.yaw_rate == -0.3


def test_targets_round_trip_through_the_codec():
    msg = mixed_target(0.5, 0.1, 2.5, -0.3, stamp=5.0)
    assert codec.decode(PositionTarget, codec.encode(msg)) == msg


@pytest.mark.parametrize(
    "bad", [math.nan, math.inf, -math.inf, True, False, "1.0", None, [1.0], 1 + 2j]
)
def test_bad_values_are_rejected_as_value_and_type_errors(bad):
    with pytest.raises(InvalidArgument) as info:
        velocity_target(bad, 0.0, 0.0, 0.0, stamp=1.0)
    assert "vx" in str(info.value)
    assert isinstance(info.value, ValueError)
    assert isinstance(info.value, TypeError)


@pytest.mark.parametrize("field", ["x", "y", "z", "yaw"])
def test_each_position_field_is_checked(field):
    args = {"x": 0.0, "y": 0.0, "z": 0.0, "yaw": 0.0, field: math.nan}
    with pytest.raises(InvalidArgument, match=field):
        position_target(args["x"], args["y"], args["z"], args["yaw"], stamp=1.0)


def test_numpy_and_int_numbers_are_accepted():
    assert finite("v", np.float32(1.5)) == 1.5
    assert finite("v", np.int64(2)) == 2.0
    assert finite("v", 3) == 3.0
    with pytest.raises(InvalidArgument):
        finite("v", np.float64("nan"))
    with pytest.raises(InvalidArgument):
        finite("v", np.bool_(True))


def test_stamp_defaults_to_now_and_must_be_a_positive_epoch():
    assert check_stamp(None, 123.0) == 123.0
    assert check_stamp(1.7e9, 123.0) == 1.7e9
    for bad in (0.0, -1.0, math.nan, "now"):
        with pytest.raises(InvalidArgument):
            check_stamp(bad, 123.0)
