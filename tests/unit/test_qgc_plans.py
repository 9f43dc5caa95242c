"""QGroundControl plans as people write them (sdk/dronewrapper/plan.py, plan_fence.py), read
from the files in tests/data/qgc_plans (QGroundControl's .plan structure; SOURCES.md there):
null altitudes refused naming the item, AMSL kept AMSL, surveys and corridor scans flown as
their expanded items, the fence folded into the envelope or refused, never dropped."""

from __future__ import annotations

import math
import re
from pathlib import Path

import pytest

from dronewrapper import envelope as env
from dronewrapper.envelope import Envelope, EnvelopeError
from dronewrapper.geodesy import to_enu
from dronewrapper.msgs.mission import NAV_RALLY_POINT
from dronewrapper.plan import PlanError, read_plan, waypoints_of
from dronewrapper.plan_fence import CIRCLE_VERTICES, PlanFence, fold, rally_waypoints

PLANS = Path(__file__).resolve().parents[1] / "data" / "qgc_plans"
HOME = (47.3977419, 8.5455938, 488.0)  # the plans' plannedHomePosition


def commands(name: str) -> list[int]:
    return [wp.command for wp in read_plan(PLANS / name).waypoints]


def test_every_plan_file_is_read_or_refused_with_its_reason():
    refused = {
        "calculated_altitude.plan": re.escape(
            "mission item 2 (mission.items[2], NAV_WAYPOINT): the altitude is null"
        ),
        "structure_scan.plan": r"mission.items\[1\]: a StructureScan ComplexItem without its "
        "expanded items",
    }
    files = sorted(PLANS.glob("*.plan"))
    assert len(files) >= 10
    for path in files:
        if path.name in refused:
            with pytest.raises(PlanError, match=refused[path.name]):
                read_plan(path)
        else:
            assert read_plan(path).waypoints, path.name


def test_a_square_keeps_its_items_frames_and_relative_altitudes():
    plan = read_plan(PLANS / "square_relative.plan")
    assert [wp.command for wp in plan.waypoints] == [22, 16, 16, 16, 16, 20]
    assert {wp.frame for wp in plan.waypoints[:5]} == {3}
    assert [wp.z_alt for wp in plan.waypoints[:5]] == [10, 10, 10, 12, 12]
    assert plan.fence.empty


def test_amsl_items_stay_amsl_and_a_null_altitude_never_becomes_0_m():
    plan = read_plan(PLANS / "amsl_altitudes.plan")
    amsl = [wp for wp in plan.waypoints if wp.frame == 0]
    assert [wp.z_alt for wp in amsl] == [493.0, 496.0]  # 5 and 8 m above the 488 m home
    with pytest.raises(PlanError, match="never 0 m AMSL"):
        read_plan(PLANS / "calculated_altitude.plan")


def test_a_survey_and_a_corridor_scan_are_flown_as_their_expanded_items():
    survey = commands("survey.plan")
    assert survey == [22, 206, 16, 16, 16, 16, 16, 16, 206, 20]  # trigger on, 6 legs, off
    assert commands("corridor_scan.plan") == [22, 16, 16, 16, 16, 16, 16, 20]
    item = read_plan(PLANS / "survey.plan").waypoints[2]
    assert (round(item.z_alt), item.frame) == (15, 3)


def test_camera_gimbal_roi_gripper_and_spline_items_are_read_as_written():
    assert commands("camera_gimbal_items.plan") == [
        22, 530, 205, 195, 178, 16, 2000, 197, 211, 16, 20,
    ]  # fmt: skip
    speed = read_plan(PLANS / "camera_gimbal_items.plan").waypoints[4]
    assert (speed.param1, speed.param2) == (1, 10)  # ground speed 10 m/s
    assert commands("spline_waypoints.plan")[2:4] == [82, 82]  # ArduPilot flies them


def test_a_null_position_of_a_waypoint_is_refused_naming_it():
    doc = {
        "fileType": "Plan",
        "mission": {"items": [{"type": "SimpleItem", "command": 16, "frame": 3,
                               "params": [0, 0, 0, None, None, 8.5, 10]}]},
    }  # fmt: skip
    with pytest.raises(PlanError, match=r"mission item 0 .*NAV_WAYPOINT.*latitude or longitude"):
        waypoints_of(doc)


def test_a_plan_fence_folds_into_the_envelope_and_binds_the_items():
    plan = read_plan(PLANS / "fence_polygon_circle.plan")
    kinds = [(z.inclusion, z.center is not None) for z in plan.fence.zones]
    assert kinds == [(True, False), (False, True)]
    folded = fold(plan.fence, Envelope(), HOME)
    assert max(abs(v) for vertex in folded.fence for v in vertex) == pytest.approx(60, abs=0.1)
    (circle,) = folded.exclusions
    assert len(circle) == CIRCLE_VERTICES
    center = to_enu(HOME, *plan.fence.zones[1].center)
    assert min(math.dist(v, center) for v in circle) >= 8.0  # around the 8 m circle
    with pytest.raises(EnvelopeError, match="exclusion zone 1"):
        env.check_position(folded, center[0] + 7.9, center[1], 8.0)
    with pytest.raises(EnvelopeError, match="outside the envelope's fence"):
        env.check_position(folded, 70.0, 0.0, 8.0)
    for wp in plan.waypoints[1:4]:  # the plan's own items fly inside
        env.check_position(folded, *to_enu(HOME, wp.x_lat, wp.y_long), wp.z_alt)
    assert fold(plan.fence, folded, HOME) == folded  # twice: the same envelope


def test_what_the_envelope_cannot_hold_is_refused_never_dropped():
    rally = read_plan(PLANS / "rally_breach_return.plan").fence
    assert len(rally.rally_points) == 2 and rally.breach_return is not None
    with pytest.raises(ValueError, match=r"a geoFence breachReturn point, which is not flown"):
        fold(rally, Envelope(), HOME)
    folded = fold(rally, Envelope(), HOME, returns_home=True)
    assert max(math.hypot(*v) for v in folded.fence) <= 150.0  # inside the inclusion circle
    no_breach_return = PlanFence(zones=rally.zones, rally_points=rally.rally_points)
    assert fold(no_breach_return, Envelope(), HOME) == folded  # rally points are uploaded
    two = read_plan(PLANS / "two_inclusion_zones.plan").fence
    with pytest.raises(ValueError, match="2 inclusion zones"):
        fold(two, Envelope(), HOME)
    square = [(-5.0, -5.0), (5.0, -5.0), (5.0, 5.0), (-5.0, 5.0)]
    fenced = read_plan(PLANS / "fence_polygon_circle.plan").fence
    with pytest.raises(ValueError, match="would replace the envelope's fence"):
        fold(fenced, Envelope(fence=square), HOME)


def test_far_distances_read_in_metres_and_kilometres():
    assert env.metres(8843410.0) == "8843.4 km"
    assert env.metres(1113.19) == "1113.19 m"
    reason = env.violation(Envelope(), 8_000_000.0, 4_000_000.0, 5.0)
    assert "e+" not in reason and "8944.3 km" in reason


def test_rally_points_become_rally_items_above_home():
    fence = read_plan(PLANS / "rally_breach_return.plan").fence
    items = rally_waypoints(fence)
    assert [(i.command, i.frame) for i in items] == [(NAV_RALLY_POINT, 3)] * 2
    assert [(i.x_lat, i.y_long, i.z_alt) for i in items] == list(fence.rally_points)
    assert rally_waypoints(PlanFence()) == []
    assert not PlanFence(rally_points=fence.rally_points).folds  # nothing for the envelope
