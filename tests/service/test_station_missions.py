"""The station's mission and fence: the map's data (home, mission, envelope) in a drone's
snapshot, a ``.plan`` uploaded from the page, mission start and return, with the real bridge
and the simulator behind the fake bus (tests/bus_bridge.py), the app driven in process."""

from __future__ import annotations

import math

import pytest
from asgi_driver import AsgiClient
from bus_bridge import EPOCH, SimBridge

from dronewrapper.envelope import Envelope
from dronewrapper.geodesy import to_geodetic
from dronewrapper.runtime.fake import FakeBus, FakeNode
from dronewrapper_ground_station.access import Access
from dronewrapper_ground_station.app import create_app
from dronewrapper_ground_station.config import Config
from dronewrapper_ground_station.fleet import Fleet
from dronewrapper_ground_station.node import PORTS

HOME = (47.397742, 8.545594)
FENCE = [(-30.0, -30.0), (30.0, -30.0), (30.0, 30.0), (-30.0, 30.0)]
FAST_RTL = {"RTL_RETURN_ALT": 6.0, "RTL_DESCEND_ALT": 3.0, "RTL_LAND_DELAY": 0.0}


class Station:
    def __init__(self) -> None:
        self.bus = FakeBus(start=EPOCH)
        self.pair = SimBridge(self.bus, envelope=Envelope(fence=FENCE), params=FAST_RTL)
        self.node = FakeNode("station", self.bus, ports=PORTS)
        config = Config(port=0, command_timeout=120.0)
        self.fleet = Fleet(self.node, config)
        self.client = AsgiClient(create_app(self.fleet, config, Access("operator-token-0123")))
        self.fleet.discover()
        self.run(3.0)

    def run(self, seconds: float) -> None:
        self.bus.clock.run_for(seconds)

    def post(self, command: str, body: dict | None = None):
        return self.client.http("POST", f"/api/drones/drone/{command}", body or {})

    def snapshot(self) -> dict:
        return self.client.http("GET", "/api/drones/drone")[1]

    def close(self) -> None:
        self.client.close()
        self.fleet.close()
        self.pair.close()


@pytest.fixture
def station():
    rig = Station()
    yield rig
    rig.close()


def plan_of(points: list[tuple[float, float, float]]) -> dict:
    items = []
    for x, y, z in points:
        lat, lon = to_geodetic(HOME, x, y)
        params = [0, 0.5, 0, None, lat, lon, z]
        items.append({"type": "SimpleItem", "command": 16, "frame": 3, "params": params})
    return {"fileType": "Plan", "version": 1, "mission": {"items": items}}


def test_the_snapshot_carries_home_and_the_fence_for_the_map(station):
    snap = station.snapshot()
    assert snap["home"]["latitude"] == pytest.approx(HOME[0], abs=1e-6)
    assert snap["envelope"]["fence"] == [list(v) for v in FENCE]
    assert snap["envelope"]["max_distance"] == 500.0


def test_a_plan_uploaded_from_the_page_is_flown_and_the_drone_returns(station):
    assert station.post("takeoff", {"height": 4.0})[0] == 200
    status, reply, _ = station.post("upload_plan", {"plan": plan_of([(6, 0, 4), (6, 6, 4)])})
    assert status == 200, reply
    mission = station.snapshot()["mission"]
    assert len(mission["items"]) == 2
    assert mission["items"][1]["y"] == pytest.approx(to_geodetic(HOME, 6, 6)[1])
    start = station.pair.t
    assert station.post("start_mission")[0] == 200
    station.run(20.0)
    assert station.pair.closest_approach((6.0, 6.0, 4.0), start) <= 1.0
    assert station.post("rtl")[0] == 200
    assert math.hypot(*station.pair.position[:2]) <= 1.0 and not station.pair.autopilot.armed


def test_bad_plans_are_refused_with_the_reason(station):
    status, reply, _ = station.post("upload_plan", {"plan": "not a plan"})
    assert status == 400 and "plan must be" in reply["error"]
    survey = {"fileType": "Plan", "mission": {"items": [{"type": "ComplexItem"}]}}
    status, reply, _ = station.post("upload_plan", {"plan": survey})
    assert status == 409 and "ComplexItem without its expanded items" in reply["error"]
    status, reply, _ = station.post("upload_plan", {"plan": plan_of([(50, 0, 4)])})
    assert status == 409 and "outside the envelope's fence" in reply["error"]
