"""bridge_tello's envelope and missions (missions.py): refusals naming the limit, the breach
landing, local missions flown as go moves."""

from __future__ import annotations

import math

import pytest
from tello_core_rig import TelloRig

from dronewrapper.envelope import Envelope
from dronewrapper.msgs import registry
from dronewrapper.msgs.flight import NO_HOME, REFUSED, GotoRequest, ReturnRequest
from dronewrapper.msgs.geometry import Point, Vector3
from dronewrapper.msgs.mavros import (
    FRAME_BODY_NED,
    FRAME_LOCAL_NED,
    LANDED_STATE_IN_AIR,
    MASK_MIXED,
    MASK_POSITION,
    CommandTOL,
    PositionTarget,
)
from dronewrapper.msgs.mission import NAV_RALLY_POINT, MissionControl, Waypoint, WaypointPush
from dronewrapper.runtime import ServiceError
from dronewrapper_bridge_tello import actions, missions
from dronewrapper_bridge_tello import operations as ops
from dronewrapper_bridge_tello.config import Config


def local(x: float, y: float, z: float) -> Waypoint:
    return Waypoint(frame=missions.FRAME_LOCAL_ENU, x_lat=x, y_long=y, z_alt=z)


def flying_rig(**config) -> TelloRig:
    rig = TelloRig(**config)
    rig.connect()
    assert rig.call(ops.takeoff, CommandTOL.takeoff()).success
    assert rig.core.telemetry.landed.state == LANDED_STATE_IN_AIR
    rig.run(0.5)  # the state strings after the take-off: 1 m up
    return rig


def test_the_tello_default_envelope_is_10_m_up_and_30_m_out():
    envelope = Config().envelope
    assert (envelope.max_altitude, envelope.max_distance) == (10.0, 30.0)


def test_go_moves_turn_an_enu_offset_into_the_heading_frame():
    assert missions.go_moves(3.0, 0.0, 0.0, 0.0) == [(300, 0, 0)]
    assert missions.go_moves(0.0, 2.0, 0.0, 0.0) == [(0, 200, 0)]  # north is left facing east
    assert missions.go_moves(0.0, 2.0, 0.0, math.pi / 2) == [(200, 0, 0)]  # facing north
    assert missions.go_moves(0.1, 0.1, 0.1, 0.0) == []  # go refuses moves within 20 cm


def test_go_moves_split_legs_longer_than_5_m():
    moves = missions.go_moves(12.0, 0.0, 1.0, 0.0)
    assert len(moves) == 3 and all(abs(v) <= 500 for move in moves for v in move)
    assert [sum(axis) for axis in zip(*moves, strict=True)] == [1200, 0, 100]


def test_a_takeoff_above_the_envelope_is_refused():
    rig = TelloRig()
    rig.connect()
    with pytest.raises(ServiceError, match="take-off altitude 25 m above the envelope's 10 m"):
        rig.call(ops.takeoff, CommandTOL.takeoff(altitude=25.0))
    assert "takeoff" not in rig.commands()


def test_a_position_beyond_the_envelope_is_refused():
    rig = flying_rig()
    target = PositionTarget(
        coordinate_frame=FRAME_LOCAL_NED, type_mask=MASK_POSITION, position=Point(x=40.0, z=1.0)
    )
    rig.setpoint(target)
    assert rig.core.rejected_setpoints == 1
    texts = [m.text for m in rig.published(registry.STATUSTEXT)]
    assert any("distance 40 m from home beyond the envelope's 30 m" in t for t in texts)


def test_a_target_above_the_envelope_is_refused_and_flies_nothing():
    rig = flying_rig()
    above = PositionTarget(
        coordinate_frame=FRAME_LOCAL_NED, type_mask=MASK_POSITION, position=Point(x=1.0, z=12.0)
    )
    climb = PositionTarget(
        coordinate_frame=FRAME_BODY_NED,
        type_mask=MASK_MIXED,
        velocity=Vector3(x=0.5),
        position=Point(z=12.0),
    )
    for target in (above, climb):
        start = rig.now
        rig.setpoint(target)
        rig.run(0.3)
        assert all(sticks == (0, 0, 0, 0) for _, sticks in rig.rcs(start))  # no climb
    assert rig.core.rejected_setpoints == 2
    texts = [m.text for m in rig.published(registry.STATUSTEXT)]
    assert any("altitude 12 m above the envelope's 10 m" in t for t in texts)


def test_a_breach_lands_the_tello():
    rig = flying_rig(envelope=Envelope(max_altitude=3.0, margin=0.5, breach_action="land"))
    start = rig.now
    rig.height_cm = 400  # blown up to 4 m
    rig.run(1.0)
    assert "land" in rig.commands(start)
    texts = [m.text for m in rig.published(registry.STATUSTEXT)]
    assert any("envelope breach: altitude 4 m above the envelope's 3 m; land" in t for t in texts)


def test_a_local_mission_is_flown_as_go_moves_and_reports_each_item():
    rig = flying_rig()
    reply = rig.call(missions.push, WaypointPush(waypoints=[local(3, 0, 1), local(3, 3, 1)]))
    assert reply.success and reply.wp_transfered == 2
    start = rig.now
    assert rig.call(missions.control, MissionControl(action="start")).success
    rig.run(2.0)
    assert rig.commands(start) == ["go 300 0 0 50", "go 300 300 0 50"]
    assert [m.wp_seq for m in rig.published(registry.MISSION_REACHED)] == [0, 1]


def test_a_global_mission_is_refused_honestly():
    rig = flying_rig()
    with pytest.raises(ServiceError, match="the Tello has no GPS"):
        rig.call(
            missions.push, WaypointPush(waypoints=[Waypoint(x_lat=47.0, y_long=8.0, z_alt=5.0)])
        )


def test_rally_points_are_refused_by_the_tello_and_an_empty_list_is_taken():
    rig = flying_rig()
    rally = [Waypoint(frame=4, command=NAV_RALLY_POINT, x_lat=2.0, y_long=0.0, z_alt=1.0)]
    with pytest.raises(ServiceError, match=r"the Tello has no rally points \(1 given\)"):
        rig.call(missions.push, WaypointPush(waypoints=[local(1, 0, 1)], rally=rally))
    assert rig.call(missions.push, WaypointPush(waypoints=[local(1, 0, 1)], rally=[])).success


def test_a_mission_item_outside_the_envelope_is_refused():
    rig = flying_rig()
    with pytest.raises(ServiceError, match="mission item 1: altitude 12 m above"):
        rig.call(missions.push, WaypointPush(waypoints=[local(1, 0, 1), local(1, 0, 12)]))


def test_the_tello_goto_and_return_are_one_operation_each_and_refused_on_the_ground():
    grounded = TelloRig()
    grounded.connect()
    reply = grounded.call(actions.goto_point, GotoRequest(x=3.0, y=0.0, z=1.0))
    assert reply.failure == REFUSED and "not flying" in reply.message
    rig = flying_rig()
    geodetic = GotoRequest(latitude=47.0, longitude=8.0, z=1.0)
    assert rig.call(actions.goto_point, geodetic).failure == NO_HOME
    start = rig.now
    reply = rig.call(actions.goto_point, GotoRequest(x=3.0, y=0.0, z=1.0))
    assert reply.success, reply.message
    assert rig.commands(start) == ["go 300 0 0 50"]
    reply = rig.call(actions.return_home, ReturnRequest())
    assert reply.success, reply.message
    assert rig.commands(start)[-1] == "land"  # (the rig's Tello does not move: home is here)


def test_a_pause_then_resume_before_the_move_ends_goes_on():
    rig = flying_rig()
    assert rig.call(missions.push, WaypointPush(waypoints=[local(3, 0, 1), local(3, 3, 1)])).success
    assert rig.call(missions.control, MissionControl(action="start")).success
    assert rig.call(missions.control, MissionControl(action="pause")).success
    reply = rig.call(missions.control, MissionControl(action="start"))
    assert reply.success and "resumed" in reply.message
    rig.run(2.0)
    assert [m.wp_seq for m in rig.published(registry.MISSION_REACHED)] == [0, 1]
