"""Mission items placed by their frame and checked against the envelope as heights above home
(bridge_mavlink/mission_frames.py): local items are metres, not degrees; AMSL altitudes are
compared with the ceiling after home's altitude is taken off."""

from __future__ import annotations

import math

import pytest

from dronewrapper.envelope import Envelope
from dronewrapper.geodesy import to_enu
from dronewrapper.msgs.mission import Waypoint
from dronewrapper.plan import waypoints_of
from dronewrapper_bridge_mavlink import mission_frames as mf

HOME = (47.397742, 8.545594, 488.0)
ENVELOPE = Envelope(max_altitude=15.0, max_distance=500.0)


def test_a_local_mission_is_placed_in_metres_and_uploaded_as_global_items():
    local = waypoints_of([(3, 0, 3), (3, 3, 3), (0, 0, 3)], frame="local")
    out = mf.prepare(local, ENVELOPE, HOME)
    for wp, (x, y, z) in zip(out, [(3, 0, 3), (3, 3, 3), (0, 0, 3)], strict=True):
        assert wp.frame == 3  # GLOBAL_RELATIVE_ALT: what the autopilot flies
        east, north = to_enu(HOME, wp.x_lat, wp.y_long)
        assert math.dist((east, north, wp.z_alt), (x, y, z)) < 0.01


def test_a_local_item_outside_the_envelope_is_refused_in_metres():
    local = waypoints_of([(3, 0, 3), (0, 0, 20)], frame="local")
    with pytest.raises(mf.MissionFrameError, match="mission item 1: altitude 20 m above"):
        mf.prepare(local, ENVELOPE, HOME)


def test_an_amsl_item_is_compared_with_the_ceiling_as_height_above_home():
    ok = Waypoint(frame=0, x_lat=HOME[0], y_long=HOME[1], z_alt=493.0)  # 5 m above home
    assert mf.placed(ok, HOME) == pytest.approx((0.0, 0.0, 5.0))
    assert mf.prepare([ok], ENVELOPE, HOME) == [ok]
    high = Waypoint(frame=5, x_lat=HOME[0], y_long=HOME[1], z_alt=510.0)  # 22 m above home
    with pytest.raises(mf.MissionFrameError, match="altitude 22 m above the envelope's 15 m"):
        mf.prepare([high], ENVELOPE, HOME)


def test_relative_and_terrain_items_are_heights_above_home():
    for frame in (3, 6, 10, 11):
        wp = Waypoint(frame=frame, x_lat=HOME[0], y_long=HOME[1], z_alt=12.0)
        assert mf.placed(wp, HOME) == pytest.approx((0.0, 0.0, 12.0))


def test_items_without_position_and_unknown_home():
    speed = Waypoint(frame=2, command=178, x_lat=0.0, y_long=0.0, z_alt=0.0, param2=5.0)
    assert mf.placed(speed, HOME) is None
    far = Waypoint(x_lat=HOME[0] + 0.01, y_long=HOME[1], z_alt=5.0)
    with pytest.raises(mf.MissionFrameError, match="home is not known yet"):
        mf.prepare([far], ENVELOPE, None)
    local = waypoints_of([(3, 0, 3)], frame="local")
    with pytest.raises(mf.MissionFrameError, match="needs home's latitude and longitude"):
        mf.prepare(local, ENVELOPE, None)
    with pytest.raises(mf.MissionFrameError, match="frame 7 is not a mission frame"):
        mf.placed(Waypoint(frame=7, x_lat=1.0, y_long=1.0, z_alt=1.0), HOME)
