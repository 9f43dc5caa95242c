"""Plan files written by QGroundControl itself (tests/data/qgc_plans/mavsdk: MAVSDK's test data,
BSD-3-Clause, copied unchanged; README.md there gives each file's source and sha256): read as
QGroundControl wrote them, or refused naming the item and why."""

from __future__ import annotations

import hashlib
import re
from pathlib import Path

import pytest

from dronewrapper.plan import PlanError, read_plan

PLANS = Path(__file__).resolve().parents[1] / "data" / "qgc_plans" / "mavsdk"


def commands(name: str) -> list[int]:
    return [wp.command for wp in read_plan(PLANS / name).waypoints]


def test_the_files_are_the_copies_the_readme_names():
    readme = (PLANS / "README.md").read_text()
    listed = dict(re.findall(r"^\| (\S+) \| `([0-9a-f]{64})`", readme, re.M))
    files = {p.name for p in PLANS.iterdir() if p.name != "README.md"}
    assert set(listed) == files
    for name, digest in listed.items():
        assert hashlib.sha256((PLANS / name).read_bytes()).hexdigest() == digest, name


def test_a_sample_mission_keeps_its_items_frames_and_altitudes():
    plan = read_plan(PLANS / "qgroundcontrol_sample.plan")
    # take-off, waypoint, IMAGE_START_CAPTURE, two waypoints, return
    assert [wp.command for wp in plan.waypoints] == [22, 16, 2000, 16, 16, 20]
    flown = [wp for wp in plan.waypoints if wp.command in (16, 22)]
    assert {wp.frame for wp in flown} == {3} and {wp.z_alt for wp in flown} == {50.0}
    assert plan.fence.empty


def test_a_survey_is_read_as_the_items_qgroundcontrol_expanded_it_into():
    # SET_CAMERA_MODE, then the survey: 8 waypoints and the camera trigger distance set four
    # times, the last one (trigger off) after the last waypoint
    assert commands("qgroundcontrol_sample_with_survey.plan") == [
        530, 16, 206, 16, 206, 16, 16, 16, 16, 206, 16, 16, 206,
    ]  # fmt: skip


def test_a_camera_only_mission_is_read():
    assert commands("qgroundcontrol_sample_with_digicam_control.plan") == [203]


@pytest.mark.parametrize(
    ("name", "kind"),
    [
        ("qgroundcontrol_sample_with_survey_missing_items.plan", "survey"),
        ("qgroundcontrol_sample_with_structured_scan.plan", "StructureScan"),
    ],
)
def test_a_complex_item_without_its_expanded_items_is_refused_naming_it(name, kind):
    with pytest.raises(PlanError, match=rf"mission.items\[1\]: a {kind} ComplexItem without"):
        read_plan(PLANS / name)
