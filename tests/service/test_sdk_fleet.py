"""The SDK's fleet on the fake bus: drones found online with their kind and health, commanded
all at once, one outcome per drone, a slow drone never holding the others back.

Each drone is a :class:`~bus_autopilot.SdkRig` of its own (its own bus and bus time, so that
each drone's blocking call moves only its own aircraft); their liveliness tokens are gathered
on one directory bus, where the fleet looks for bridges.
"""

from __future__ import annotations

import asyncio
import threading

import pytest
from bus_autopilot import TELEMETRY_PERIOD_S, SdkRig

from dronewrapper import CommandRefused, DroneWrapper, NotConnected, Timeout
from dronewrapper.aio import Fleet as AsyncFleet
from dronewrapper.fleet import Fleet, FleetError
from dronewrapper.fleet_online import bridges_online, wait_for_bridges
from dronewrapper.msgs import registry
from dronewrapper.msgs.mavros import MASK_POSITION
from dronewrapper.runtime.fake import FakeBus, FakeNode

REAL_WAIT_S = 30.0
"""A generous bound on real time for a call that must finish (the fake bus runs at once)."""


class FleetRig:
    """Drones ``drone1..droneN`` (``autopilots``: one per drone) on their own fake buses."""

    def __init__(self, *autopilots: dict) -> None:
        self.rigs: dict[str, SdkRig] = {}
        self.directory = FakeBus()
        for i, autopilot in enumerate(autopilots, start=1):
            name = f"drone{i}"
            rig = SdkRig({"ns": name, **autopilot}, open_drone=False)
            rig.drone = DroneWrapper(name, **rig.options())
            rig.run(TELEMETRY_PERIOD_S)
            self.directory.tokens |= rig.bus.tokens
            self.rigs[name] = rig
        finder = FakeNode("app", self.directory)
        self.fleet = Fleet(
            {name: rig.drone for name, rig in self.rigs.items()},
            alive=lambda: finder.alive_services("*"),
        )

    def close(self) -> None:
        self.fleet.close()
        for rig in self.rigs.values():
            rig.close()


@pytest.fixture
def trio():
    rig = FleetRig({}, {"autopilot": "tello"}, {})
    yield rig
    rig.close()


def test_drones_online_with_their_kind_and_health(trio):
    infos = trio.fleet.online()
    assert [(i.name, i.bridge, i.kind) for i in infos] == [
        ("drone1", "bridge_fake", "px4"), ("drone2", "bridge_fake", "tello"),
        ("drone3", "bridge_fake", "px4"),
    ]  # fmt: skip
    assert all(i.connected and i.healthy and i.battery == pytest.approx(0.8) for i in infos)
    quiet = trio.rigs["drone3"].bus.clock
    quiet.advance_to(quiet() + 2.0)  # drone3's telemetry stops arriving
    health = {i.name: i.healthy for i in trio.fleet.online()}
    assert health == {"drone1": True, "drone2": True, "drone3": False}


def test_take_off_all_and_land_all_return_one_outcome_per_drone(trio):
    result = trio.fleet.takeoff(h=1.0, timeout=20).raise_errors()
    assert sorted(result) == ["drone1", "drone2", "drone3"] and result.ok
    for rig in trio.rigs.values():
        assert rig.drone.get_position()[2] >= 0.9
    assert [name for _, name in trio.rigs["drone2"].pilot.calls] == ["flight_takeoff"]  # a Tello
    assert trio.fleet.land(timeout=20).ok
    assert not any(rig.drone.is_flying() for rig in trio.rigs.values())


def test_a_refusal_is_that_drones_outcome_only():
    rig = FleetRig({}, {}, {"refuse": {"arming": "battery too low"}})
    try:
        result = rig.fleet.arm()
        assert result.results() == {"drone1": None, "drone2": None}
        assert isinstance(result["drone3"].error, CommandRefused)
        assert "battery too low" in str(result.failed["drone3"])
        with pytest.raises(FleetError, match=r"arming failed on 1 of 3: drone3: .*battery too low"):
            result.raise_errors()
    finally:
        rig.close()


def test_a_drone_that_does_not_answer_never_holds_the_others_back(trio):
    arming = registry.ARMING.key("drone2")
    services = trio.rigs["drone2"].bus._services
    answer, gate = services[arming], threading.Event()

    def slow_answer(*args):
        gate.wait(REAL_WAIT_S)  # drone2 answers only when the test lets it
        return answer(*args)

    services[arming] = slow_answer
    futures = trio.fleet.submit(lambda d: d.arm())
    for name in ("drone1", "drone3"):  # each future holds (the call's value, its seconds)
        value, seconds = futures[name].result(REAL_WAIT_S)
        assert value is None and 0.0 <= seconds < REAL_WAIT_S
    assert not futures["drone2"].done()  # still waiting for its reply
    result = trio.fleet.collect(futures, wait_s=0.0, what="arming")
    assert result["drone1"].ok and result["drone3"].ok
    assert isinstance(result["drone2"].error, Timeout) and "drone2 still busy" in str(
        result["drone2"].error
    )
    assert [name for _, name in trio.rigs["drone1"].pilot.calls] == ["arming"]
    again = trio.fleet.each(lambda d: d.ns, ["drone1", "drone3"])  # their workers are free
    assert again.results() == {"drone1": "drone1", "drone3": "drone3"}
    gate.set()
    assert futures["drone2"].result(REAL_WAIT_S)[0] is None  # its reply came, late


def test_formation_setpoints_go_to_each_drone_in_its_own_frame(trio):
    trio.fleet.takeoff(h=1.0, timeout=20).raise_errors()
    result = trio.fleet.formation(
        {"drone1": (0.0, 0.0), "drone2": (2.0, 0.0), "drone3": (0.0, 2.0, 3.0)},
        center=(1.0, 1.0),
        z=2.0,
        origins={"drone2": (3.0, 1.0, 0.0)},
    )
    assert result.ok
    expected = {"drone1": (1.0, 1.0, 2.0), "drone2": (0.0, 0.0, 2.0), "drone3": (1.0, 3.0, 3.0)}
    for name, rig in trio.rigs.items():
        target = rig.pilot.setpoints()[-1][1]
        assert target.type_mask == MASK_POSITION
        got = (target.position.x, target.position.y, target.position.z)
        assert got == pytest.approx(expected[name]), name
    bad = trio.fleet.set_cmd_pos({"drone1": (0.0, 0.0, float("nan"))})
    assert not bad.ok and "drone1" in bad.failed
    with pytest.raises(KeyError, match="not in this fleet: drone9"):
        trio.fleet.set_cmd_pos({"drone9": (0.0, 0.0, 1.0)})


def test_the_asyncio_fleet_awaits_each_drone_and_yields_outcomes_as_they_end(trio):
    async def main():
        fleet = AsyncFleet(fleet=trio.fleet)
        assert len(fleet) == 3 and [i.name for i in fleet.online()] == fleet.names
        result = await fleet.takeoff(h=1.0, timeout=20)
        ended = [o async for o in fleet.as_completed(lambda d: d.land(timeout=20))]
        return result, ended

    result, ended = asyncio.run(asyncio.wait_for(main(), REAL_WAIT_S))
    assert result.ok and sorted(o.name for o in ended) == ["drone1", "drone2", "drone3"]
    assert all(o.ok for o in ended)


def test_bridges_are_found_by_liveliness_and_waited_for():
    keys = {"drone10/alive/bridge_mavlink", "drone2/alive/bridge_tello", "drone2/alive/sim",
            "drone3/alive/camera"}  # fmt: skip
    assert bridges_online(keys) == {"drone2": "bridge_tello", "drone10": "bridge_mavlink"}
    seen = iter([set(), {"drone1/alive/bridge_mavlink"}, keys])
    got = wait_for_bridges(lambda: next(seen), None, 2, 1e9, interval=0.0)
    assert list(got) == ["drone2", "drone10"]
    with pytest.raises(NotConnected, match=r"no bridge online for drone7 \(online: drone2"):
        wait_for_bridges(lambda: keys, ["drone2", "drone7"], None, deadline=0.0)
