"""The SDK's side of the bridge's refusals: what it can know it raises at the call (a setpoint
outside the envelope it holds, an envelope it cannot be), what only the bridge knows arrives
as a warning line, the ``refusals`` view, ``on_refusal`` callbacks and, in ``aio``, an async
iterator; an envelope set by a commander is named to the next one on connect. The simulator
flown through bridge_mavlink's real bridge on the fake bus (tests/bus_bridge.py), in bus time."""

from __future__ import annotations

import asyncio
import logging

import pytest
from bus_bridge import SimSdk

from dronewrapper import DroneWrapper
from dronewrapper.aio import Drone
from dronewrapper.envelope import Envelope
from dronewrapper.errors import CommandRefused, InvalidArgument
from dronewrapper.fleet import Fleet
from dronewrapper.msgs import registry
from dronewrapper.msgs.refusal import Refusal
from dronewrapper.msgs.std import Header
from dronewrapper.runtime.fake import FakeBus, FakeNode

FENCE = [(-10.0, -10.0), (10.0, -10.0), (10.0, 10.0), (-10.0, 10.0)]
LEASE = Refusal(
    header=Header(stamp=1_700_000_000.0),
    commander="ada",
    kind="lease",
    limit="command_lease",
    message="'bob' holds the command lease; 'ada' must take it over explicitly",
)


@pytest.fixture
def sim():
    rig = SimSdk()
    yield rig
    rig.close()


def test_a_setpoint_outside_the_envelope_held_raises_naming_the_limit_and_sends_nothing(sim):
    sim.drone.set_envelope(max_altitude=15.0, fence=FENCE)
    sim.drone.takeoff(3.0)
    sim.drone.stop_commanding()
    cases = [
        (lambda: sim.drone.set_cmd_pos(30.0, 0.0, 3.0), "fence", "outside the envelope's fence"),
        (lambda: sim.drone.set_cmd_pos(0.0, 0.0, 20.0), "max_altitude", "above the envelope's 15"),
        (lambda: sim.drone.set_cmd_vel(vx=15.0), "max_horizontal_speed", "12 m/s"),
        (lambda: sim.drone.set_cmd_mix(z=20.0), "max_altitude", "above the envelope's 15 m"),
    ]
    for call, limit, words in cases:
        with pytest.raises(CommandRefused, match=words) as refused:
            call()
        assert refused.value.limit == limit
        assert sim.drone.commanding is None
    assert sim.pair.core.rejected_setpoints == 0  # nothing reached the bridge
    sim.drone.set_cmd_pos(5.0, 0.0, 3.0)  # inside: flown
    sim.run(8.0)
    assert abs(sim.pair.position[0] - 5.0) < 1.0


def test_set_envelope_refuses_a_useless_ceiling_a_wrong_type_and_a_fence_away_from_home(sim):
    with pytest.raises(InvalidArgument, match=r"max_altitude.*at least 1 m"):
        sim.drone.set_envelope(max_altitude=0.1)
    with pytest.raises(InvalidArgument, match="max_altitude: Expected `float`, got `str`"):
        sim.drone.set_envelope(max_altitude="high")
    with pytest.raises(InvalidArgument, match="fence"):
        sim.drone.set_envelope(fence=[(0.0, 0.0), (1.0, "x"), (2.0, 2.0)])
    away = [(20.0, 20.0), (30.0, 20.0), (30.0, 30.0), (20.0, 30.0)]
    with pytest.raises(CommandRefused, match="fence contains neither home nor the aircraft"):
        sim.drone.set_envelope(fence=away)
    assert sim.drone.envelope() == Envelope()  # nothing changed
    assert sim.drone.set_envelope(max_altitude=1.0).max_altitude == 1.0  # the minimum itself


def test_an_envelope_set_by_a_commander_is_named_to_the_next_one_and_can_be_reset(sim, caplog):
    sim.drone.set_envelope(max_altitude=15.0, fence=FENCE, max_horizontal_speed=5.0)
    caplog.set_level(logging.WARNING, logger="dronewrapper")
    nxt = DroneWrapper("drone", node=FakeNode("next", sim.bus), wait=False, commander="eve")
    try:
        nxt.wait_for_connection(5.0)
        warned = [r.getMessage() for r in caplog.records if "envelope in force" in r.getMessage()]
        assert len(warned) == 1
        assert "set by" in warned[0] and "max_altitude 15 m" in warned[0]
        assert "reset_envelope()" in warned[0]
        with pytest.raises(CommandRefused, match="above the envelope's 5 m/s"):  # held from
            nxt.set_cmd_vel(vx=6.0)  # the connect on
        assert nxt.commanding is None
        assert nxt.reset_envelope() == Envelope()  # the bridge's configured one
    finally:
        nxt.close()
    caplog.clear()
    again = DroneWrapper("drone", node=FakeNode("again", sim.bus), wait=False)
    try:
        again.wait_for_connection(5.0)
        assert not [r for r in caplog.records if "envelope in force" in r.getMessage()]
    finally:
        again.close()


def test_a_refusal_reaches_the_view_the_callback_and_one_warning_line(caplog):
    bus = FakeBus(start=1_700_000_000.0)
    bridge = FakeNode("bridge", bus).publisher(registry.REFUSAL)
    drone = DroneWrapper("drone", node=FakeNode("app", bus), wait=False, commander="ada")
    heard: list[Refusal] = []
    stop = drone.on_refusal(heard.append)
    caplog.set_level(logging.WARNING, logger="dronewrapper")
    try:
        bridge.put(LEASE)
        bridge.put(Refusal(commander="bob", kind="envelope", message="not ours"))
        bus.clock.advance_to(bus.clock.monotonic() + 1.0)
        bridge.put(LEASE)  # the same again within 5 s: kept and called back, not warned
        assert drone.refusals == [LEASE, LEASE] and heard == [LEASE, LEASE]
        lines = [r.getMessage() for r in caplog.records if "refused" in r.getMessage()]
        assert lines == [
            "drone: setpoint refused (lease, command_lease): 'bob' holds the command lease; "
            "'ada' must take it over explicitly"
        ]
        stop()
        bridge.put(LEASE)
        assert len(heard) == 2 and len(drone.refusals) == 3
    finally:
        drone.close()


def test_aio_refusals_are_an_async_iterator_that_keeps_each_one():
    bus = FakeBus(start=1_700_000_000.0)
    bridge = FakeNode("bridge", bus).publisher(registry.REFUSAL)

    async def main() -> list[Refusal]:
        node = FakeNode("app", bus)
        async with Drone("drone", node=node, wait=False, commander="ada") as drone:
            stream = drone.refusal_stream()
            first = asyncio.ensure_future(stream.__anext__())
            while not drone.sync.client.refusals._listeners:  # the iterator has started listening
                await asyncio.sleep(0)
            bridge.put(LEASE)
            bridge.put(Refusal(commander="ada", kind="late", limit="late_setpoint_s"))
            got = [await first, await stream.__anext__()]
            await stream.aclose()
            assert not drone.sync.client.refusals._listeners
            return got

    got = asyncio.run(asyncio.wait_for(main(), 60))
    assert [r.kind for r in got] == ["lease", "late"]


def test_a_fleet_names_the_drone_each_refusal_came_from():
    bus = FakeBus(start=1_700_000_000.0)
    node = FakeNode("app", bus)
    drones = {ns: DroneWrapper(ns, node=node, wait=False, commander="ada") for ns in ("d1", "d2")}
    fleet = Fleet(drones, owns=True)
    heard: list[tuple[str, str]] = []
    stop = fleet.on_refusal(lambda name, refusal: heard.append((name, refusal.kind)))
    try:
        FakeNode("bridge", bus, ns="d2").publisher(registry.REFUSAL).put(LEASE)
        assert heard == [("d2", "lease")]
        assert fleet.refusals() == {"d1": [], "d2": [LEASE]}
        stop()
        FakeNode("bridge", bus, ns="d1").publisher(registry.REFUSAL).put(LEASE)
        assert heard == [("d2", "lease")] and fleet.refusals()["d1"] == [LEASE]
    finally:
        fleet.close()
