"""The setpoint rules every bridge shares: the three controls, their frames, finite fields
(bools are not numbers) and the bridge's bounds, each refusal naming the field."""

from __future__ import annotations

import math

import msgspec
import pytest
from targets import velocity

from dronewrapper.msgs.geometry import Point, Vector3
from dronewrapper.msgs.mavros import (
    FRAME_BODY_NED,
    FRAME_LOCAL_NED,
    MASK_MIXED,
    MASK_POSITION,
    PositionTarget,
)
from dronewrapper_bridge_base.setpoint_limits import Kind, SetpointError, validate
from dronewrapper_bridge_mavlink.setpoints import Limits


class Bounds(msgspec.Struct, frozen=True):
    max_distance: float = 50.0
    min_altitude: float = 0.0
    max_altitude: float = 30.0
    max_horizontal_speed: float = 3.0
    max_vertical_speed: float = 2.0
    max_yaw_rate: float = math.pi


def test_the_three_controls_are_recognised():
    pos = PositionTarget(
        coordinate_frame=FRAME_LOCAL_NED, type_mask=MASK_POSITION, position=Point(x=1, y=2, z=3)
    )
    mix = PositionTarget(
        coordinate_frame=FRAME_BODY_NED,
        type_mask=MASK_MIXED,
        velocity=Vector3(x=1.0),
        position=Point(z=2.0),
    )
    assert validate(pos, Bounds()) is Kind.POSITION
    assert validate(velocity(1.0), Bounds()) is Kind.VELOCITY
    assert validate(velocity(1.0, frame=FRAME_LOCAL_NED), Bounds()) is Kind.VELOCITY
    assert validate(mix, Bounds()) is Kind.MIXED


@pytest.mark.parametrize(
    "target, words",
    [
        (velocity(math.nan), "velocity.x must be a finite number"),
        (velocity(True), "velocity.x must be a finite number"),
        (velocity(yaw_rate=math.inf), "yaw_rate must be a finite number"),
        (velocity(4.0), "horizontal speed 4 m/s exceeds 3"),
        (velocity(vz=-2.5), "vertical speed -2.5 m/s exceeds 2"),
        (velocity(yaw_rate=4.0), "yaw_rate 4 rad/s exceeds"),
        (
            PositionTarget(coordinate_frame=FRAME_LOCAL_NED, type_mask=MASK_POSITION),
            "position is required",
        ),
        (
            PositionTarget(
                coordinate_frame=FRAME_BODY_NED, type_mask=MASK_POSITION, position=Point(z=1.0)
            ),
            "coordinate_frame 8 is not valid with type_mask 3064",
        ),
        (
            PositionTarget(
                coordinate_frame=FRAME_LOCAL_NED, type_mask=MASK_POSITION, position=Point(x=60.0)
            ),
            "farther than 50 m",
        ),
        (
            PositionTarget(
                coordinate_frame=FRAME_LOCAL_NED, type_mask=MASK_POSITION, position=Point(z=31.0)
            ),
            "altitude z=31 m is outside [0, 30]",
        ),
        (PositionTarget(coordinate_frame=FRAME_BODY_NED, type_mask=0), "type_mask 0"),
    ],
)
def test_refusals_name_the_field(target: PositionTarget, words: str):
    with pytest.raises(SetpointError) as refused:
        validate(target, Bounds())
    assert words in str(refused.value)


def test_a_bridge_config_section_is_bounds():
    """bridge_mavlink's ``limits`` section is used as it is."""
    assert validate(velocity(19.0), Limits()) is Kind.VELOCITY
    with pytest.raises(SetpointError, match="horizontal speed"):
        validate(velocity(21.0), Limits())


def test_both_bridges_refuse_in_the_same_words():
    from dronewrapper_bridge_mavlink import setpoints as mavlink_setpoints
    from dronewrapper_bridge_tello import sticks as tello_sticks
    from dronewrapper_bridge_tello.sticks import StickScale

    for bad in (velocity(True), velocity(math.nan), velocity(yaw_rate=9.0)):
        with pytest.raises(SetpointError) as by_mavlink:
            mavlink_setpoints.validate(bad, Limits())
        with pytest.raises(SetpointError) as by_tello:
            tello_sticks.validate(bad, StickScale())
        assert str(by_mavlink.value) == str(by_tello.value)


def test_a_target_without_its_position_says_so_where_it_is_read():
    """``required_position`` is how bridges read a position or mixed target's position: a
    target that left it out raises ValueError naming the mask, never an AttributeError."""
    left_out = PositionTarget(coordinate_frame=FRAME_LOCAL_NED, type_mask=MASK_MIXED)
    with pytest.raises(ValueError, match=f"position is required with type_mask {MASK_MIXED}"):
        left_out.required_position()
    given = PositionTarget(
        coordinate_frame=FRAME_LOCAL_NED, type_mask=MASK_POSITION, position=Point(x=1.0, z=2.0)
    )
    assert given.required_position() == Point(x=1.0, z=2.0)
