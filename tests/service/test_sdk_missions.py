"""The SDK's go-to, return, missions and envelope (dronewrapper/missions.py), flying the
simulator through bridge_mavlink's real bridge on the fake bus (tests/bus_bridge.py), in bus
time, judged from the simulator's ground truth."""

from __future__ import annotations

import asyncio
import json
import math

import pytest
from bus_bridge import EPOCH, HOME, SimBridge, SimSdk, returning_sim

from dronewrapper import DroneWrapper
from dronewrapper.aio import Drone
from dronewrapper.errors import CommandRefused, InvalidArgument, NoData
from dronewrapper.geodesy import to_geodetic
from dronewrapper.runtime.fake import FakeBus, FakeNode


@pytest.fixture
def sim():
    yield from returning_sim(6.0)


def near(rig: SimSdk, x: float, y: float, z: float) -> float:
    return math.dist(rig.pair.position, (x, y, z))


def test_takeoff_above_the_envelope_is_refused_naming_the_limit(sim):
    with pytest.raises(CommandRefused, match="altitude 500 m above the envelope's 120 m"):
        sim.drone.takeoff(h=500)
    assert not sim.pair.autopilot.armed


def test_goto_local_and_goto_arrive_within_1_m_and_refuse_outside_the_envelope(sim):
    sim.drone.takeoff(5.0)
    sim.drone.goto_local(10.0, 0.0, 5.0)
    assert near(sim, 10.0, 0.0, 5.0) <= 1.0
    lat, lon = to_geodetic(HOME, 10.0, 6.0)
    sim.drone.goto(lat, lon, 4.0)
    assert near(sim, 10.0, 6.0, 4.0) <= 1.0
    with pytest.raises(CommandRefused, match="distance 600 m from home beyond the envelope's 500"):
        sim.drone.goto_local(600.0, 0.0, 5.0)
    envelope = sim.drone.set_envelope(max_altitude=30.0)
    assert envelope.max_altitude == 30.0 and envelope.max_distance == 500.0
    with pytest.raises(CommandRefused, match="altitude 40 m above the envelope's 30 m"):
        sim.drone.goto_local(0.0, 0.0, 40.0)
    assert sim.pair.core.rejected_setpoints == 0  # refused before anything reached the bridge
    with pytest.raises(InvalidArgument, match="unknown field"):
        sim.drone.set_envelope(ceiling=3)


def test_a_waypoint_list_is_flown_and_progress_reported_then_rtl_lands_at_home(sim):
    sim.drone.takeoff(5.0)
    points = [(8.0, 0.0, 5.0), (8.0, 8.0, 5.0)]
    plan = [(*to_geodetic(HOME, x, y), z) for x, y, z in points]
    assert sim.drone.upload_mission(plan) == 2
    before = sim.drone.mission_progress()  # no item reached yet: None, not -1
    assert (before.total, before.reached, before.finished) == (2, None, False)
    start = sim.pair.t
    sim.drone.start_mission()
    for _ in range(600):
        sim.run(0.1)
        if sim.drone.mission_progress().finished:
            break
    progress = sim.drone.mission_progress()
    assert (progress.total, progress.reached) == (2, 1)
    assert all(sim.pair.closest_approach(p, start) <= 1.0 for p in points)
    sim.drone.return_to_launch()
    assert math.hypot(*sim.pair.position[:2]) <= 1.0 and not sim.pair.autopilot.armed


def test_a_qgroundcontrol_plan_is_uploaded(sim, tmp_path):
    lat, lon = to_geodetic(HOME, 5.0, 5.0)
    item = {"type": "SimpleItem", "command": 16, "frame": 3, "autoContinue": True}
    plan = {
        "fileType": "Plan",
        "mission": {"items": [{**item, "params": [0, 0.5, 0, None, lat, lon, 6]}]},
    }
    path = tmp_path / "one.plan"
    path.write_text(json.dumps(plan))
    assert sim.drone.upload_mission(path) == 1
    assert sim.pair.autopilot.missions.mission[0].x == round(lat * 1e7)
    survey = {**plan, "mission": {"items": [{"type": "ComplexItem"}]}}
    path.write_text(json.dumps(survey))
    with pytest.raises(InvalidArgument, match="ComplexItem without its expanded items"):
        sim.drone.upload_mission(path)


def test_a_mission_item_outside_the_envelope_is_refused(sim):
    far = [(*to_geodetic(HOME, 0.0, 700.0), 5.0)]
    with pytest.raises(CommandRefused, match="mission item 0: distance 700 m"):
        sim.drone.upload_mission(far)


def test_the_aio_front_awaits_the_envelope_and_goto(sim):
    async def ask() -> None:
        drone = Drone("drone", node=sim.node, wait=False)
        await drone.connect()
        try:
            envelope = await drone.set_envelope(max_distance=50.0)
            assert envelope.max_distance == 50.0
            with pytest.raises(CommandRefused, match="distance 60 m from home beyond"):
                await drone.goto_local(60.0, 0.0, 3.0)
        finally:
            await drone.close()

    asyncio.run(ask())


def test_calls_with_nothing_to_do_are_refused_at_once_naming_the_call(sim):
    start = sim.bus.clock()
    with pytest.raises(CommandRefused, match="goto refused: not flying"):
        sim.drone.goto_local(2.0, 0.0, 3.0)
    with pytest.raises(CommandRefused, match="no mission uploaded"):
        sim.drone.start_mission()
    with pytest.raises(CommandRefused, match="no mission is being flown"):
        sim.drone.pause_mission()
    with pytest.raises(CommandRefused, match="return refused: not flying"):
        sim.drone.return_to_launch()
    assert sim.bus.clock() - start < 5.0  # no call waited out a timeout
    assert not sim.pair.autopilot.armed and sim.pair.autopilot.mode.name == "LOITER"


def test_a_mission_left_by_its_program_ends_on_the_ground_at_home(sim):
    sim.drone.takeoff(3.0)
    sim.drone.upload_mission([(8.0, 0.0, 3.0), (8.0, 8.0, 3.0)], frame="local")
    sim.drone.start_mission()
    sim.run(2.0)
    sim.drone.close()  # the program ends: its beats stop
    for _ in range(90):
        sim.run(1.0)
        if not sim.pair.autopilot.armed:
            break
    assert not sim.pair.autopilot.armed, sim.pair.autopilot.mode.name
    assert sim.pair.core.missions.last_reached == 1  # finished first
    assert math.hypot(*sim.pair.position[:2]) < 1.0


def test_goto_local_before_home_is_known_never_flies_a_guess():
    """Right after connecting home may not be known yet (HOME_POSITION comes at 0.5-1 Hz):
    the autopilot armed 6 m east of its local origin, so a guess of (0, 0, 0) flies 6 m off.
    With HOME_POSITION held back, goto_local raises NoData and the drone stays; once home
    arrives it flies to the point from home (ground truth)."""
    bus = FakeBus(start=EPOCH)
    pair = SimBridge(bus, start=(6.0, 0.0))
    held = {"HOME_POSITION"}
    to_bridge = pair.link._to_bridge
    pair.link._to_bridge = lambda msgs: to_bridge([m for m in msgs if m.get_type() not in held])
    drone = DroneWrapper("drone", node=FakeNode("app", bus), wait=False)
    try:
        bus.clock.run_for(3.0)
        drone.takeoff(3.0)
        with pytest.raises(NoData, match="home"):
            drone.goto_local(2.0, 0.0, 3.0)
        assert abs(pair.position[0] - 6.0) < 0.5  # it did not fly a guess
        held.clear()
        drone.goto_local(2.0, 0.0, 3.0)
        assert math.dist(pair.position, (8.0, 0.0, 3.0)) <= 1.0
    finally:
        drone.close()
        pair.close()
