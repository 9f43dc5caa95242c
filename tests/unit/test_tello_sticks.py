"""PositionTarget -> Tello rc sticks: signs (a right, d clockwise), scale, clamping, loops."""

from __future__ import annotations

import math

import msgspec
import pytest
from targets import velocity

from dronewrapper.msgs.geometry import Point
from dronewrapper.msgs.mavros import (
    FRAME_BODY_NED,
    FRAME_LOCAL_NED,
    MASK_MIXED,
    MASK_POSITION,
    PositionTarget,
)
from dronewrapper_bridge_tello.sticks import (
    Kind,
    SetpointError,
    StickScale,
    body_velocity,
    rc_command,
    sticks_from_flu,
    validate,
)

SCALE = StickScale()


def test_signs_flu_ccw_to_tello_sticks():
    assert sticks_from_flu(0.5, 0, 0, 0, SCALE) == (0, 50, 0, 0)  # forward -> b > 0
    assert sticks_from_flu(0, 0.3, 0, 0, SCALE) == (-30, 0, 0, 0)  # left -> a < 0 (a > 0 right)
    assert sticks_from_flu(0, 0, 0.2, 0, SCALE) == (0, 0, 20, 0)  # up -> c > 0
    assert sticks_from_flu(0, 0, 0, 0.5, SCALE)[3] < 0  # CCW -> d < 0 (d > 0 clockwise)
    assert sticks_from_flu(0, 0, 0, -0.5, SCALE)[3] == round(0.5 * SCALE.yaw)


def test_sticks_are_clamped_integers_and_zero_is_a_real_stop():
    sticks = sticks_from_flu(5.0, -5.0, 3.0, -9.0, SCALE)
    assert sticks == (100, 100, 100, 100)
    assert all(isinstance(s, int) for s in sticks)
    small = StickScale(max_stick=40)
    assert sticks_from_flu(-5.0, 5.0, -3.0, 9.0, small) == (-40, -40, -40, -40)
    assert rc_command(sticks_from_flu(0, 0, 0, 0, SCALE)) == "rc 0 0 0 0"
    assert rc_command((-3, 4, 0, 100)) == "rc -3 4 0 100"


def test_calibrated_scale():
    scale = StickScale(horizontal=80.0, vertical=120.0, yaw=40.0)
    assert sticks_from_flu(0.5, 0.25, 0.5, 1.0, scale) == (-20, 40, 60, -40)


def test_body_velocity_passes_through():
    t = velocity(0.4, -0.1, 0.2, 0.3)
    assert body_velocity(t, validate(t, SCALE), (0, 0, 1), 1.0, SCALE) == (0.4, -0.1, 0.2, 0.3)


def test_local_velocity_rotated_into_the_body():
    t = velocity(0.0, 0.5, frame=FRAME_LOCAL_NED)  # north at 0.5 m/s
    vx, vy, _, _ = body_velocity(t, validate(t, SCALE), (0, 0, 1), 0.0, SCALE)  # facing east
    assert (vx, vy) == pytest.approx((0.0, 0.5))  # north is left of an east-facing drone


def test_mixed_holds_altitude_on_the_estimate():
    t = velocity(0.3, 0.0, mask=MASK_MIXED)
    t = msgspec.structs.replace(t, position=Point(z=2.0))
    _, _, vz, _ = body_velocity(t, validate(t, SCALE), (0, 0, 1.8), 0.0, SCALE)
    assert vz == pytest.approx(0.2)
    _, _, vz, _ = body_velocity(t, Kind.MIXED, (0, 0, 0.0), 0.0, SCALE)
    assert vz == pytest.approx(SCALE.position_climb)  # clamped


def test_position_loop_flies_towards_the_target_and_turns_the_short_way():
    t = PositionTarget(
        coordinate_frame=FRAME_LOCAL_NED,
        type_mask=MASK_POSITION,
        position=Point(x=0.0, y=10.0, z=1.0),
        yaw=-3.0,
    )
    vx, vy, vz, yaw_rate = body_velocity(t, validate(t, SCALE), (0, 0, 1), math.pi / 2, SCALE)
    assert vx == pytest.approx(SCALE.position_speed) and abs(vy) < 1e-9  # facing north
    assert vz == pytest.approx(0.0)
    # from yaw 90 deg to -3 rad (~ -172 deg): the short way is counter-clockwise
    assert yaw_rate > 0


@pytest.mark.parametrize(
    "target, reason",
    [
        (velocity(vx=float("nan")), "finite"),
        (velocity(vx=float("inf")), "finite"),
        (velocity(vx=5.0), "horizontal speed"),
        (velocity(vz=-3.0), "vertical speed"),
        (velocity(yaw_rate=20.0), "yaw_rate"),
        (velocity(mask=1234), "type_mask"),
        (velocity(frame=7), "coordinate_frame"),
        (PositionTarget(coordinate_frame=FRAME_BODY_NED, type_mask=MASK_POSITION), "frame"),
    ],
)
def test_bad_setpoints_are_refused(target, reason):
    with pytest.raises(SetpointError, match=reason):
        validate(target, SCALE)


def test_position_target_bounds():
    t = PositionTarget(coordinate_frame=FRAME_LOCAL_NED, type_mask=MASK_POSITION)
    with pytest.raises(SetpointError, match="position is required"):
        validate(t, SCALE)  # left out: never the origin
    t = msgspec.structs.replace(t, position=Point(z=50.0))
    with pytest.raises(SetpointError, match="altitude"):
        validate(t, SCALE)
    t = msgspec.structs.replace(t, position=Point(x=500.0, z=1.0))
    with pytest.raises(SetpointError, match="farther"):
        validate(t, SCALE)
