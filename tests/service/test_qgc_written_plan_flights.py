"""Plans written by QGroundControl itself (tests/data/qgc_plans/mavsdk, MAVSDK's test data)
uploaded and flown through the SDK and bridge_mavlink's core on the simulator
(tests/bus_bridge.py), in bus time, judged from the simulator's ground truth; and a second
mission after a first, whose progress starts afresh."""

from __future__ import annotations

from pathlib import Path

import pytest
from bus_bridge import HOME, SimSdk, assert_each_waypoint_passed, returning_sim

from dronewrapper.errors import InvalidArgument
from dronewrapper.geodesy import to_geodetic

PLANS = Path(__file__).resolve().parents[1] / "data" / "qgc_plans" / "mavsdk"


@pytest.fixture
def sim():
    yield from returning_sim(10.0)


def flown(sim: SimSdk, plan: Path, items: int, within_s: float) -> float:
    """``plan`` uploaded (``items`` items) and flown from 5 m up, for at most ``within_s`` s
    of bus time; the autopilot's time at the start."""
    assert sim.drone.upload_mission(plan) == items
    sim.drone.takeoff(5.0)
    start = sim.pair.t
    sim.fly_mission(within_s)
    return start


def test_the_sample_mission_is_flown_and_its_camera_item_skipped_with_a_note(sim):
    plan = PLANS / "qgroundcontrol_sample.plan"
    start = flown(sim, plan, 6, 120.0)
    assert sim.drone.mission_progress().finished  # its last item: return to launch
    assert_each_waypoint_passed(sim, plan, start)
    texts = [t.text for t in sim.drone.status_texts]
    assert "Mission item 2: IMAGE_START_CAPTURE skipped (no camera, gimbal or gripper)" in texts


def test_a_survey_ending_in_a_camera_item_reads_finished_after_its_last_waypoint(sim):
    # its last item turns the camera trigger off; no autopilot reports such an item reached
    plan = PLANS / "qgroundcontrol_sample_with_survey.plan"
    start = flown(sim, plan, 13, 400.0)
    progress = sim.drone.mission_progress()
    assert progress.finished and progress.reached == 11, progress
    assert progress.reached_items == (1, 3, 5, 6, 7, 8, 10, 11)  # the eight waypoints
    assert_each_waypoint_passed(sim, plan, start)


@pytest.mark.parametrize(
    ("name", "kind"),
    [
        ("qgroundcontrol_sample_with_survey_missing_items.plan", "survey"),
        ("qgroundcontrol_sample_with_structured_scan.plan", "StructureScan"),
    ],
)
def test_a_plan_that_cannot_fly_is_refused_before_anything_is_uploaded(sim, name, kind):
    with pytest.raises(InvalidArgument, match=rf"mission.items\[1\]: a {kind} ComplexItem"):
        sim.drone.upload_mission(PLANS / name)
    assert sim.drone.mission_progress().total == 0


def test_a_second_mission_is_not_finished_by_the_first_ones_last_item(sim):
    sim.drone.takeoff(5.0)
    first = [(6.0, 0.0, 5.0), (6.0, 6.0, 5.0)]
    sim.drone.upload_mission(first, frame="local")
    sim.fly_mission(60.0)
    assert sim.drone.mission_progress().finished
    second = [(*to_geodetic(HOME, x, y), z) for x, y, z in [(0.0, 6.0, 5.0), (0.0, 0.0, 5.0)]]
    sim.drone.upload_mission(second)
    progress = sim.drone.mission_progress()
    assert progress.reached is None and not progress.finished, progress
    start = sim.pair.t
    sim.fly_mission(60.0)
    assert sim.drone.mission_progress().finished
    # flown from its first item (PX4 keeps the last mission's current item through an upload
    # that marks none: the bridge marks the first)
    assert sim.pair.closest_approach((0.0, 6.0, 5.0), start) <= 1.0
