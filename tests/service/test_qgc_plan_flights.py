"""QGroundControl plans uploaded and flown through the SDK and bridge_mavlink's bridge on the
simulator (tests/bus_bridge.py), in bus time, judged from the simulator's ground truth: the
plan's fence reaches the envelope, its rally points the autopilot (checked against the
envelope), payload items are taken and skipped, a speed change is flown, an item the autopilot
refuses is named, every item reached is counted."""

from __future__ import annotations

import itertools
import json
import math
from pathlib import Path

import pytest
from bus_bridge import HOME, assert_each_waypoint_passed, returning_sim

from dronewrapper.errors import CommandRefused, InvalidArgument
from dronewrapper.geodesy import to_geodetic
from dronewrapper.msgs.mission import NAV_RALLY_POINT
from dronewrapper.plan import read_plan
from dronewrapper.plan_fence import rally_waypoints

RALLY = 2  # MAV_MISSION_TYPE_RALLY
PLANS = Path(__file__).resolve().parents[1] / "data" / "qgc_plans"


@pytest.fixture
def sim():
    yield from returning_sim(10.0)


def test_every_item_reached_is_counted(sim):
    sim.drone.takeoff(5.0)
    points = [(6.0, 0.0, 5.0), (6.0, 6.0, 5.0), (0.0, 6.0, 5.0)]
    assert sim.drone.upload_mission([(*to_geodetic(HOME, x, y), z) for x, y, z in points]) == 3
    sim.fly_mission(60.0)
    progress = sim.drone.mission_progress()
    assert progress.reached_items == (0, 1, 2) and progress.reached_count == 3
    assert progress.reached == 2


def test_a_plan_fence_reaches_the_envelope_and_binds_the_items(sim):
    path = PLANS / "fence_polygon_circle.plan"
    assert sim.drone.upload_mission(path) == 5
    envelope = sim.drone.envelope()
    assert len(envelope.fence) == 4 and len(envelope.exclusions) == 1
    document = json.loads(path.read_text())
    into_circle = document["mission"]["items"][2]
    into_circle["params"][4:6] = document["geoFence"]["circles"][0]["circle"]["center"]
    with pytest.raises(CommandRefused, match=r"mission item 2: .*exclusion zone 1"):
        sim.drone.upload_mission(document)
    assert len(sim.drone.envelope().exclusions) == 1  # the same zone, not twice


def test_rally_points_are_uploaded_to_the_autopilot_with_the_plan(sim):
    path = PLANS / "rally_breach_return.plan"
    with pytest.raises(InvalidArgument, match="a geoFence breachReturn point"):
        sim.drone.upload_mission(path)
    assert sim.drone.envelope().fence == []  # nothing was changed
    assert sim.drone.upload_mission(path, returns_home=True) == 4
    assert len(sim.drone.envelope().fence) == 24
    held = sim.pair.autopilot.missions.lists[RALLY]
    plan = read_plan(path).fence.rally_points
    assert [(i.command, i.frame) for i in held] == [(NAV_RALLY_POINT, 3)] * 2
    assert [(i.x, i.y, i.z) for i in held] == [
        (round(lat * 1e7), round(lon * 1e7), alt) for lat, lon, alt in plan
    ]
    assert sim.pair.core.missions.rally == rally_waypoints(read_plan(path).fence)
    # a plan without rally points clears the autopilot's
    assert sim.drone.upload_mission(PLANS / "square_relative.plan") > 0
    assert sim.pair.autopilot.missions.lists[RALLY] == []


def test_a_rally_point_outside_the_plans_fence_is_refused_naming_it(sim):
    document = json.loads((PLANS / "rally_breach_return.plan").read_text())
    document["rallyPoints"]["points"][1][:2] = to_geodetic(HOME, 0.0, 200.0)  # fence: 150 m
    with pytest.raises(CommandRefused, match=r"rally point 1: .*outside the envelope's fence"):
        sim.drone.upload_mission(document, returns_home=True)
    assert sim.drone.envelope().fence == []  # put back: nothing was uploaded
    assert sim.pair.autopilot.missions.lists[RALLY] == []
    document["rallyPoints"]["points"][1][:3] = [*to_geodetic(HOME, 0.0, 20.0), 200.0]
    with pytest.raises(CommandRefused, match=r"rally point 1: altitude 200 m above"):
        sim.drone.upload_mission(document, returns_home=True)


def test_a_return_lands_at_the_closest_rally_point_as_px4s(sim):
    document = json.loads((PLANS / "square_relative.plan").read_text())
    document["rallyPoints"] = {"points": [[*to_geodetic(HOME, 40.0, 0.0), 10.0]], "version": 2}
    sim.drone.upload_mission(document)
    sim.drone.takeoff(5.0)
    sim.drone.goto_local(15.0, 0.0, 5.0)  # home is the closer: 15 m against 25 m
    sim.drone.return_to_launch()
    assert math.hypot(*sim.pair.position[:2]) <= 1.0 and not sim.pair.autopilot.armed
    sim.drone.takeoff(5.0)
    sim.drone.goto_local(30.0, 0.0, 5.0)  # 10 m from the rally point, 30 m from home
    sim.drone.return_to_launch()
    east, north, _ = sim.pair.position
    assert math.hypot(east - 40.0, north) <= 1.0 and not sim.pair.autopilot.armed


def test_an_item_the_autopilot_refuses_is_named_with_its_command(sim):
    with pytest.raises(CommandRefused, match=r"at item 2 \(NAV_SPLINE_WAYPOINT, frame 3\)"):
        sim.drone.upload_mission(PLANS / "spline_waypoints.plan")


def test_payload_items_are_skipped_and_the_speed_change_is_flown(sim):
    assert sim.drone.upload_mission(PLANS / "camera_gimbal_items.plan") == 11
    sim.drone.takeoff(10.0)
    start = sim.pair.t
    sim.fly_mission(90.0)
    progress = sim.drone.mission_progress()
    assert 5 in progress.reached_items and 9 in progress.reached_items
    truth = [(t, p) for t, p, _ in sim.pair.truth if t >= start]
    speeds = [
        math.hypot(b[0] - a[0], b[1] - a[1]) / (tb - ta)
        for (ta, a), (tb, b) in itertools.pairwise(truth)
        if tb > ta
    ]
    assert 8.0 < max(speeds) < 10.8  # the 10 m/s asked, where the default is 5 m/s
    texts = [t.text for t in sim.drone.status_texts]
    assert any("DO_MOUNT_CONTROL skipped" in t for t in texts)


@pytest.mark.parametrize(
    "name",
    ["square_relative.plan", "survey.plan", "corridor_scan.plan", "fence_polygon_circle.plan"],
)
def test_a_plan_is_flown_through_each_of_its_waypoints(sim, name):
    plan = read_plan(PLANS / name)
    assert sim.drone.upload_mission(PLANS / name) == len(plan.waypoints)
    sim.drone.takeoff(5.0)
    start = sim.pair.t
    sim.fly_mission(240.0)
    progress = sim.drone.mission_progress()
    assert progress.finished and progress.reached_count >= 2
    assert_each_waypoint_passed(sim, PLANS / name, start)
