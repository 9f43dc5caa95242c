"""Scenario files: every fixed name loads, starts as the follow apps expect, and bad files fail
naming the file and the key."""

from __future__ import annotations

import math

import numpy as np
import pytest

from dronewrapper_sim.render.camera import FRONTAL, PinholeCamera, project, yaw_to_quat
from dronewrapper_sim.world.scenario import (
    SCENARIO_NAMES,
    SCENARIOS_DIR,
    ConfigError,
    RandomWalkMotion,
    WaypointsMotion,
    load_scenario,
)
from dronewrapper_sim.world.world import World

PAPER_NAMES = (
    "beacon_static",
    "beacon_smooth",
    "beacon_abrupt",
    "person_static",
    "person_moving",
    "people_crossing_behind",
    "people_crossing_front",
)


def test_the_fixed_names_are_all_there():
    assert set(PAPER_NAMES) | {"empty"} == set(SCENARIO_NAMES)
    assert {p.stem for p in SCENARIOS_DIR.glob("*.yaml")} == set(SCENARIO_NAMES)


@pytest.mark.parametrize("name", SCENARIO_NAMES)
def test_every_scenario_loads_with_its_own_name(name):
    scenario = load_scenario(name)
    assert scenario.name == name
    assert scenario.description
    assert scenario.duration_s > 0
    assert (scenario.camera.width, scenario.camera.height, scenario.camera.rate_hz) == (
        640,
        480,
        30.0,
    )
    assert 60.0 <= scenario.camera.hfov_deg <= 70.0


@pytest.mark.parametrize("name", PAPER_NAMES)
def test_the_vehicle_starts_at_the_origin_facing_its_target(name):
    scenario = load_scenario(name)
    assert (scenario.vehicle.x, scenario.vehicle.y) == (0.0, 0.0)
    world = World(scenario)
    target = world.object("target")
    cam = PinholeCamera(640, 480, math.radians(scenario.camera.hfov_deg))
    vehicle = np.array([scenario.vehicle.x, scenario.vehicle.y, 0.0])
    pixels, depth = project(
        np.array([target.center_enu, target.position, target.top_enu]),
        vehicle,
        yaw_to_quat(scenario.vehicle.yaw),
        FRONTAL,
        cam,
    )
    assert np.all(np.isfinite(pixels)) and np.all(depth > 0)
    assert np.all((pixels[:, 0] >= 0) & (pixels[:, 0] < 640))
    assert np.all((pixels[:, 1] >= 0) & (pixels[:, 1] < 480))
    distance = float(np.hypot(*target.position[:2]))
    if target.kind == "beacon":
        assert 5.0 <= distance <= 7.0
    else:
        assert 5.0 <= distance <= 8.0


def test_people_walk_at_the_papers_speeds():
    for name in PAPER_NAMES:
        for obj in load_scenario(name).objects:
            if obj.kind != "person":
                continue
            if isinstance(obj.motion, WaypointsMotion):
                assert 0.5 <= obj.motion.speed_m_s <= 1.5
            if isinstance(obj.motion, RandomWalkMotion):
                assert obj.motion.speed_min_m_s >= 0.5 and obj.motion.speed_max_m_s <= 1.5


@pytest.mark.parametrize(
    ("name", "in_front"), [("people_crossing_front", True), ("people_crossing_behind", False)]
)
def test_crossing_people_pass_across_the_line_of_sight(name, in_front):
    world = World(load_scenario(name))
    target = world.object("target")
    others = [o for o in world.objects if o.name != "target"]
    assert len(others) >= 2
    sides = {o.name: set() for o in others}
    for _ in range(40 * 10):  # 40 s
        world.step(0.1)
        for o in others:
            assert (o.position[0] < target.position[0]) == in_front
            sides[o.name].add(bool(np.sign(o.position[1]) > 0))
    assert all(len(s) == 2 for s in sides.values())  # each crossed from one side to the other


def test_empty_has_no_objects():
    assert World(load_scenario("empty")).objects == []


def test_unknown_key_fails_naming_the_file_and_the_key(tmp_path):
    path = tmp_path / "bad.yaml"
    path.write_text("name: bad\nobjects:\n  - {name: target, kind: beacon, colour: [0, 0, 255]}\n")
    with pytest.raises(ConfigError) as err:
        load_scenario(path)
    assert "bad.yaml" in str(err.value) and "colour" in str(err.value)
    assert "objects[0]" in str(err.value)


@pytest.mark.parametrize(
    ("text", "words"),
    [
        ("name: x\ncamera: {widht: 320}\n", ["widht", "camera"]),
        ("name: x\nobjects:\n  - {name: a, kind: car}\n", ["kind"]),
        ("name: x\nobjects:\n  - {name: a, kind: person, motion: {type: fly}}\n", ["motion"]),
        (
            "name: x\nobjects:\n  - {name: a, kind: person, motion: {type: circle, "
            "center: [0, 0, 0], radius_m: -1}}\n",
            ["radius_m"],
        ),
        ("name: x\nseed: many\n", ["seed"]),
        (
            "name: x\nobjects:\n  - {name: a, kind: person}\n  - {name: a, kind: beacon}\n",
            ["duplicate"],
        ),
    ],
)
def test_bad_scenarios_fail_clearly(tmp_path, text, words):
    path = tmp_path / "bad.yaml"
    path.write_text(text)
    with pytest.raises(ConfigError) as err:
        load_scenario(path)
    for word in words:
        assert word in str(err.value)


def test_unknown_scenario_name_lists_the_known_ones():
    with pytest.raises(ConfigError, match="beacon_static"):
        load_scenario("no_such_scenario")


def test_overrides_apply_on_top_of_the_file():
    scenario = load_scenario("beacon_static", ("seed=42", "camera.width=320"))
    assert scenario.seed == 42 and scenario.camera.width == 320
