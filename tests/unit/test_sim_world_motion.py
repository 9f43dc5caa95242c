"""World objects and their motion: speeds, bounds, determinism, teleoperation."""

from __future__ import annotations

import math

import numpy as np
import pytest

from dronewrapper_sim.world.scenario import (
    CircleMotion,
    ObjectSpec,
    RandomWalkMotion,
    Scenario,
    SmoothMotion,
    TeleopMotion,
    WaypointsMotion,
    ZigZagMotion,
    load_scenario,
)
from dronewrapper_sim.world.world import World

DT = 1.0 / 30.0


def one(kind: str, motion, position=(0.0, 0.0, 0.0), seed: int = 0) -> World:
    return World(
        Scenario(
            name="t",
            seed=seed,
            objects=[ObjectSpec(name="target", kind=kind, position=position, motion=motion)],
        )
    )


def track(world: World, name: str, seconds: float, dt: float = DT) -> np.ndarray:
    """Positions (N x 3) of ``name`` sampled every ``dt`` for ``seconds``."""
    out = [world.object(name).position.copy()]
    for _ in range(round(seconds / dt)):
        world.step(dt)
        out.append(world.object(name).position.copy())
    return np.array(out)


def speeds(positions: np.ndarray, dt: float = DT) -> np.ndarray:
    return np.linalg.norm(np.diff(positions, axis=0), axis=1) / dt


def test_waypoints_pingpong_at_constant_speed():
    w = one(
        "person",
        WaypointsMotion(points=[(4.0, 0.0, 0.0), (0.0, 0.0, 0.0)], speed_m_s=0.8),
    )
    p = track(w, "target", 20.0)
    assert speeds(p) == pytest.approx(0.8, abs=1e-6)
    assert p[:, 0].min() == pytest.approx(0.0, abs=0.03)
    assert p[:, 0].max() == pytest.approx(4.0, abs=0.03)
    # 20 s at 0.8 m/s = 16 m = two full round trips: back at the start
    assert p[-1] == pytest.approx([0.0, 0.0, 0.0], abs=1e-6)


def test_a_walking_person_faces_where_they_walk_and_stays_on_the_ground():
    w = one("person", WaypointsMotion(points=[(0.0, 5.0, 3.0)], speed_m_s=1.0, mode="once"))
    track(w, "target", 2.0)
    person = w.object("target")
    assert person.position[2] == 0.0
    assert person.yaw == pytest.approx(math.pi / 2, abs=1e-3)  # north
    assert person.gait > 0.5
    phase = person.walk_phase
    w.step(0.1)
    assert person.walk_phase != phase


def test_circle_keeps_radius_and_speed():
    w = one(
        "beacon",
        CircleMotion(center=(0.0, 0.0, 2.0), radius_m=3.0, speed_m_s=1.2),
        position=(3.0, 0.0, 2.0),
    )
    p = track(w, "target", 10.0)
    assert np.hypot(p[:, 0], p[:, 1]) == pytest.approx(3.0, abs=1e-9)
    assert speeds(p)[1:] == pytest.approx(1.2, rel=1e-3)
    assert p[1, 1] > 0  # counter-clockwise from angle 0


def test_zigzag_stays_in_bounds_with_random_vertical_speeds():
    spec = ZigZagMotion(direction=(0.0, 1.0), half_width_m=4.0)
    w = one("beacon", spec, position=(6.0, 0.0, 2.5), seed=3)
    p = track(w, "target", 120.0)
    assert p[:, 2].min() >= 0.5 - 1e-9 and p[:, 2].max() <= 8.0 + 1e-9
    assert p[:, 2].min() < 0.6 and p[:, 2].max() > 7.9  # it reaches both ends
    assert np.abs(p[:, 1]).max() <= 4.0 + 1e-9
    assert p[:, 0] == pytest.approx(6.0)
    v = np.diff(p, axis=0) / DT
    # steps that neither start nor end at a limit (a turn step is partly one way, partly back)
    inside = (np.abs(p[:, 1]) < 4.0 - 1e-6) & (p[:, 2] > 0.5 + 1e-6) & (p[:, 2] < 8.0 - 1e-6)
    moving = inside[:-1] & inside[1:]
    assert moving.sum() > 0.8 * len(v)
    vertical = np.abs(v[moving, 2])
    lateral = np.abs(v[moving, 1])
    assert vertical.min() >= 0.5 - 1e-6 and vertical.max() <= 1.5 + 1e-6
    assert len(np.unique(np.round(vertical, 3))) >= 4  # a new random speed at every turn
    assert lateral == pytest.approx(1.0, abs=1e-6)
    assert (np.diff(np.sign(v[:, 1])) != 0).sum() >= 4  # the horizontal direction flips


def test_smooth_motion_starts_in_place_and_stays_within_its_amplitude():
    spec = SmoothMotion(amplitude_m=(1.0, 2.0, 1.0), period_s=(30.0, 20.0, 16.0))
    w = one("beacon", spec, position=(6.0, 0.0, 2.5), seed=2)
    p = track(w, "target", 60.0)
    assert p[0] == pytest.approx([6.0, 0.0, 2.5])
    assert np.all(np.ptp(p, axis=0) <= np.array([2.0, 4.0, 2.0]) + 1e-9)
    assert speeds(p).max() < 1.0


def test_random_walk_speeds_bounds_and_determinism():
    spec = RandomWalkMotion(center=(7.0, 0.0), radius_m=3.0, min_leg_m=1.5)
    p = track(one("person", spec, position=(6.0, 0.0, 0.0), seed=5), "target", 60.0)
    s = speeds(p)
    walking = s[s > 1e-6]
    # a step that ends one leg and starts the next can be slower on average; the rest are exact
    assert np.percentile(walking, 5) >= 0.5 - 1e-6 and walking.max() <= 1.5 + 1e-6
    assert len(np.unique(np.round(walking, 2))) >= 3
    assert np.hypot(p[:, 0] - 7.0, p[:, 1]).max() <= 3.0 + 1e-6
    again = track(one("person", spec, position=(6.0, 0.0, 0.0), seed=5), "target", 60.0)
    other = track(one("person", spec, position=(6.0, 0.0, 0.0), seed=6), "target", 60.0)
    assert np.array_equal(p, again)
    assert not np.allclose(p, other)


def test_person_moving_scenario_walks_at_the_papers_speeds():
    w = World(load_scenario("person_moving"))
    s = speeds(track(w, "target", 90.0))
    walking = s[s > 0.05]
    assert walking.size > 0.3 * s.size
    assert np.percentile(walking, 5) >= 0.5 - 1e-6 and walking.max() <= 1.5 + 1e-6


def test_a_long_step_is_split_and_matches_small_steps():
    spec = ZigZagMotion()
    a, b = one("beacon", spec, (6.0, 0.0, 2.5), seed=1), one("beacon", spec, (6.0, 0.0, 2.5), 1)
    a.step(10.0)
    for _ in range(200):
        b.step(0.05)
    assert a.time_s == pytest.approx(10.0)
    assert a.object("target").position == pytest.approx(b.object("target").position)
    with pytest.raises(ValueError):
        a.step(-0.1)
    with pytest.raises(ValueError):
        a.step(math.nan)


def test_teleop_follows_commands_and_stops_when_they_go_stale():
    w = one("beacon", TeleopMotion(), position=(5.0, 0.0, 2.0))
    beacon = w.object("target")
    w.step(1.0)
    assert beacon.position == pytest.approx([5.0, 0.0, 2.0])  # still without commands
    for _ in range(30):  # 1 s of fresh commands at 30 Hz
        w.set_cmd_vel("target", np.array([0.0, 1.0, 0.5]), 0.0, w.time_s)
        w.step(DT)
    assert beacon.position == pytest.approx([5.0, 1.0, 2.5], abs=1e-6)
    assert beacon.velocity == pytest.approx([0.0, 1.0, 0.5])
    w.step(0.5)  # the last command ages up to 0.5 s: still obeyed
    moved = beacon.position.copy()
    assert moved[1] == pytest.approx(1.5, abs=0.06)
    w.step(2.0)  # now stale: stopped
    assert beacon.position == pytest.approx(moved, abs=0.06)
    assert beacon.velocity == pytest.approx([0.0, 0.0, 0.0])


def test_teleop_takes_over_a_scripted_person_and_yaw_rate_turns_it():
    w = one("person", CircleMotion(center=(0.0, 0.0, 0.0), radius_m=2.0), (2.0, 0.0, 0.0))
    w.step(1.0)
    person = w.object("target")
    start = person.position.copy()
    yaw0 = person.yaw
    for _ in range(15):
        w.set_cmd_vel("target", np.array([1.0, 0.0, 3.0]), 0.5, w.time_s)
        w.step(DT)
    assert person.position[2] == 0.0  # a person ignores vertical commands
    assert person.position[0] - start[0] == pytest.approx(0.5, abs=1e-6)
    assert math.remainder(person.yaw - yaw0, math.tau) == pytest.approx(0.25, abs=1e-6)
    w.step(3.0)  # obeyed for 0.5 s more, then stale; the circle does not come back
    assert person.position[0] - start[0] == pytest.approx(1.0, abs=0.05)
    assert person.velocity == pytest.approx([0.0, 0.0, 0.0])


def test_bad_teleop_commands_are_refused():
    w = one("beacon", TeleopMotion(), position=(5.0, 0.0, 2.0))
    with pytest.raises(KeyError, match="target"):
        w.set_cmd_vel("nobody", np.zeros(3), 0.0, 0.0)
    with pytest.raises(ValueError):
        w.set_cmd_vel("target", np.array([math.nan, 0.0, 0.0]), 0.0, 0.0)
    with pytest.raises(ValueError):
        w.set_cmd_vel("target", np.zeros(3), math.inf, 0.0)


def test_a_beacon_never_goes_below_the_ground():
    w = one("beacon", TeleopMotion(), position=(5.0, 0.0, 1.0))
    for _ in range(60):
        w.set_cmd_vel("target", np.array([0.0, 0.0, -2.0]), 0.0, w.time_s)
        w.step(DT)
    beacon = w.object("target")
    assert beacon.position[2] == pytest.approx(beacon.radius_m)


def test_the_same_seed_gives_the_same_people_and_motion():
    a, b = (
        World(load_scenario("people_crossing_front")),
        World(load_scenario("people_crossing_front")),
    )
    c = World(load_scenario("people_crossing_front"), seed=99)
    assert [o.look for o in a.objects] == [o.look for o in b.objects]
    assert [o.look for o in a.objects] != [o.look for o in c.objects]
    assert all(1.6 <= o.height_m <= 1.9 for o in c.objects)
    for _ in range(100):
        a.step(DT)
        b.step(DT)
    assert all(
        np.array_equal(x.position, y.position) for x, y in zip(a.objects, b.objects, strict=True)
    )
