"""bridge_mavlink's rally points (missions.push, uploads.push_rally) on the pure core, over
real MAVLink bytes: a mission's rally points go up after its items as MAV_MISSION_TYPE_RALLY,
each checked against the envelope first (the one outside named, nothing sent), a refused rally
upload is reported, a push without rally points leaves the autopilot's alone."""

from __future__ import annotations

import math

import pytest
from bridge_core_rig import OFFBOARD, CoreRig
from pymavlink.dialects.v20 import common as mavlink

from dronewrapper.geodesy import to_geodetic
from dronewrapper.msgs.mission import NAV_RALLY_POINT, Waypoint, WaypointPush
from dronewrapper.runtime import ServiceError
from dronewrapper_bridge_mavlink import missions

HOME = (47.397742, 8.545594, 488.0)
MISSION = mavlink.MAV_MISSION_TYPE_MISSION
RALLY = mavlink.MAV_MISSION_TYPE_RALLY


def rig_with_home() -> CoreRig:
    rig = CoreRig(upload_fence=False).connect(mode=OFFBOARD, armed=True, flying=True)
    rig.run(0.2)
    lat, lon = round(HOME[0] * 1e7), round(HOME[1] * 1e7)
    quaternion = [1.0, 0.0, 0.0, 0.0]
    rig.deliver(
        mavlink.MAVLink_home_position_message(
            lat, lon, 488000, 0.0, 0.0, 0.0, quaternion, 0.0, 0.0, 0.0
        )
    )
    return rig


def at(east: float, north: float, up: float, **kw) -> Waypoint:
    lat, lon = to_geodetic(HOME, east, north)
    return Waypoint(x_lat=lat, y_long=lon, z_alt=up, **kw)


def rally(east: float, north: float, up: float) -> Waypoint:
    return at(east, north, up, command=NAV_RALLY_POINT)


def push(rig: CoreRig, request: WaypointPush, return_alt: float | None = 10.0):
    """Start mission/push; answer PX4's RTL_RETURN_ALT read (None: never answered)."""
    op = rig.call(missions.push, request)
    rig.run(0.1)
    if request.rally and return_alt is not None:
        rig.param("RTL_RETURN_ALT", return_alt, mavlink.MAV_PARAM_TYPE_REAL32)
    rig.run(0.1 if return_alt is not None else 20.0)
    return op


def answer(rig: CoreRig, mission_type: int, result: int = mavlink.MAV_MISSION_ACCEPTED) -> list:
    """Play the autopilot's side of the last upload; returns the items received."""
    count = rig.sent_since(-math.inf, "MISSION_COUNT")[-1]
    assert count.mission_type == mission_type
    received = []
    for seq in range(count.count):
        rig.deliver(mavlink.MAVLink_mission_request_int_message(255, 191, seq, mission_type))
        received.append(rig.sent_since(-math.inf, "MISSION_ITEM_INT")[-1])
    rig.deliver(mavlink.MAVLink_mission_ack_message(255, 191, result, mission_type))
    rig.run(0.1)
    return received


def test_rally_points_are_uploaded_after_the_mission_as_rally_items():
    rig = rig_with_home()
    points = [rally(30.0, 0.0, 15.0), rally(-20.0, 40.0, 10.0)]
    op = push(rig, WaypointPush(waypoints=[at(10, 0, 10)], rally=points))
    answer(rig, MISSION)
    assert not op.done  # the rally points follow
    items = answer(rig, RALLY)
    reply = op.result()
    assert reply.success and reply.wp_transfered == 1
    assert reply.message == "1 item(s) uploaded and 2 rally point(s)"
    assert [(i.seq, i.command, i.frame, i.mission_type) for i in items] == [
        (0, NAV_RALLY_POINT, 3, RALLY),
        (1, NAV_RALLY_POINT, 3, RALLY),
    ]
    assert [i.x for i in items] == [round(p.x_lat * 1e7) for p in points]
    assert [i.z for i in items] == [15.0, 10.0]
    assert rig.core.missions.rally == points


def test_an_empty_rally_list_clears_and_none_leaves_the_autopilots():
    rig = rig_with_home()
    op = push(rig, WaypointPush(waypoints=[at(10, 0, 10)], rally=[]))
    answer(rig, MISSION)
    assert answer(rig, RALLY) == []  # MISSION_COUNT 0 of type rally: cleared
    assert op.result().success
    op = push(rig, WaypointPush(waypoints=[at(10, 0, 10)]))
    answer(rig, MISSION)
    assert op.result().success
    counts = rig.sent_since(-math.inf, "MISSION_COUNT")
    assert [c.mission_type for c in counts] == [MISSION, RALLY, MISSION]


def test_a_local_rally_point_goes_up_as_a_global_one():
    rig = rig_with_home()
    local = Waypoint(frame=4, command=NAV_RALLY_POINT, x_lat=30.0, y_long=0.0, z_alt=12.0)
    op = push(rig, WaypointPush(waypoints=[at(10, 0, 10)], rally=[local]))
    answer(rig, MISSION)
    (item,) = answer(rig, RALLY)
    assert op.result().success
    lat, lon = to_geodetic(HOME, 30.0, 0.0)
    assert (item.frame, item.x, item.y, item.z) == (3, round(lat * 1e7), round(lon * 1e7), 12.0)


@pytest.mark.parametrize(
    ("point", "reason"),
    [
        (rally(0.0, 600.0, 10.0), r"rally point 1: distance 600 m from home beyond"),
        (rally(5.0, 0.0, 130.0), r"rally point 1: altitude 130 m above the envelope's 120 m"),
    ],
)
def test_a_rally_point_outside_the_envelope_is_refused_before_anything_is_sent(point, reason):
    rig = rig_with_home()
    request = WaypointPush(waypoints=[at(10, 0, 10)], rally=[rally(5, 5, 10), point])
    op = push(rig, request)
    with pytest.raises(ServiceError, match=reason):
        op.result()
    assert not rig.sent_since(-math.inf, "MISSION_COUNT")


def test_a_refused_rally_upload_is_reported_with_the_mission_kept():
    rig = rig_with_home()
    op = push(rig, WaypointPush(waypoints=[at(10, 0, 10)], rally=[rally(5, 5, 9)]))
    answer(rig, MISSION)
    answer(rig, RALLY, mavlink.MAV_MISSION_UNSUPPORTED)
    reply = op.result()
    assert not reply.success and reply.wp_transfered == 1
    assert "its rally points were not" in reply.message
    assert "MAV_MISSION_UNSUPPORTED" in reply.message
    assert len(rig.core.missions.waypoints) == 1 and rig.core.missions.rally == []


def test_a_push_refuses_a_rally_item_that_is_not_a_rally_point():
    with pytest.raises(ValueError, match=r"rally point 0: a NAV_RALLY_POINT \(5100\)"):
        WaypointPush(waypoints=[], rally=[at(1, 1, 5)])
    with pytest.raises(ValueError, match="at most 100 rally points"):
        WaypointPush(rally=[rally(1, 1, 5)] * 101)


def test_on_px4_a_rally_point_whose_return_climbs_above_the_ceiling_is_refused():
    """PX4 returns at the rally point's altitude plus RTL_RETURN_ALT: the sum is bound."""
    rig = rig_with_home()
    request = WaypointPush(waypoints=[at(10, 0, 10)], rally=[rally(30, 0, 15)])
    op = push(rig, request, return_alt=110.0)
    with pytest.raises(ServiceError, match=r"rally point 0: a return there climbs to 125 m"):
        op.result()
    op = push(rig, request, return_alt=None)  # unanswered: the bound the bridge keeps, 119 m
    with pytest.raises(ServiceError, match=r"climbs to 134 m above home .* the envelope's 120 m"):
        op.result()
    assert not rig.sent_since(-math.inf, "MISSION_COUNT")
    op = push(rig, request, return_alt=100.0)
    answer(rig, MISSION)
    answer(rig, RALLY)
    assert op.result().success
