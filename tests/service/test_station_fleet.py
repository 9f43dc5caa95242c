"""The station's commands for a classroom: land every drone at once, and reset a simulated
drone to its start (``{ns}/sim/world/reset``), on the fake bus in bus time (see station_rig)."""

from __future__ import annotations

import logging
import threading

import pytest
from bus_autopilot import BusAutopilot, drive
from station_rig import TOKEN, StationRig

from dronewrapper.msgs import registry
from dronewrapper.msgs.simulation import VehicleResetResult
from dronewrapper.runtime import ServiceError
from dronewrapper.runtime.fake import FakeNode

pytestmark = pytest.mark.timeout(60)
AUTH = {"X-Station-Token": TOKEN}


class ClassroomRig(StationRig):
    """The station with two more drones in the air (``drone2``, ``drone3``); the landings run on
    threads of their own, so the bus moves under a lock."""

    def __init__(self) -> None:
        self._lock = threading.RLock()
        self.others: list[BusAutopilot] = []
        super().__init__()
        for ns in ("drone2", "drone3"):
            self.others.append(BusAutopilot(self.bus, flying=True, ns=ns))
        self.fleet.discover()
        self.run(0.2)

    def run(self, seconds: float) -> None:
        with self._lock:
            drive(self.bus, self.bus.clock() + seconds, self.pilot, self.world, *self.others)

    def run_until(self, until: float, done) -> None:
        """The bus clock's stepper (each landing's waits): every aircraft ticks."""
        with self._lock:
            drive(self.bus, until, self.pilot, self.world, *self.others, stop=done)


def test_land_all_lands_every_drone_and_says_how_each_went():
    rig = ClassroomRig()
    try:
        rig.others[1].refuse["flight_land"] = "landing denied"
        status, reply, _ = rig.http("POST", "/api/fleet/land", {}, AUTH)
        assert status == 200 and reply["ok"] is False
        assert reply["drones"]["drone"] == "landed" and reply["drones"]["drone2"] == "landed"
        assert "landing denied" in reply["drones"]["drone3"]
        assert rig.pilot.called("flight_land") == 1 and rig.others[0].called("flight_land") == 1
        landed = rig.http("GET", "/api/drones/drone2")[1]["landed"]["landed_state"]
        assert landed == "on_ground"
    finally:
        rig.close()


def test_land_all_needs_the_operator():
    rig = StationRig()
    try:
        status, _, _ = rig.http("POST", "/api/fleet/land", {}, {"Host": "station.example:8080"})
        assert status == 403 and rig.pilot.called("land") == 0
    finally:
        rig.close()


def test_reset_asks_the_drones_own_simulator_and_stops_commanding():
    rig = StationRig()
    sim = FakeNode("sim", rig.bus, ns="drone")
    asked = []

    def reset(request):
        asked.append(request)
        return VehicleResetResult(success=True, message="back at its start")

    sim.serve(registry.SIM_RESET, reset)
    try:
        rig.http("POST", "/api/drones/drone/goto", {"x": 2.0, "y": 0.0}, AUTH)
        assert rig.link.drone.commanding is not None
        status, reply, _ = rig.http("POST", "/api/drones/drone/reset", {}, AUTH)
        assert status == 200 and reply["ok"] is True and len(asked) == 1
        assert rig.link.drone.commanding is None  # no old setpoint drives it from the start
        assert rig.link.last_command["what"] == "reset"

        def refuse(_request):
            raise ServiceError("the loop is stopped")

        sim.serve(registry.SIM_RESET, refuse)
        status, reply, _ = rig.http("POST", "/api/drones/drone/reset", {}, AUTH)
        assert status == 409 and "the loop is stopped" in reply["error"]
    finally:
        rig.close()


def test_reset_of_a_real_aircraft_says_no_simulator_answers():
    rig = StationRig()
    try:
        status, reply, _ = rig.http("POST", "/api/drones/drone/reset", {}, AUTH)
        assert status == 503 and "no simulator answers" in reply["error"]
    finally:
        rig.close()


def test_the_terminal_says_when_the_router_is_unreachable_and_when_it_is_back(caplog):
    rig = StationRig()
    with caplog.at_level(logging.INFO, logger="station"):
        rig.bus.link_gap(True)
        rig.fleet.discover()
        rig.fleet.discover()  # said once, not at every discovery
        rig.bus.link_gap(False)
        rig.fleet.discover()
    said = [(r.levelno, r.getMessage()) for r in caplog.records if r.name == "station"]
    unreachable = [text for level, text in said if level == logging.WARNING]
    assert len(unreachable) == 1 and unreachable[0].startswith(
        "no router reachable at the router: the page shows no drone until one runs there"
    )
    assert (logging.INFO, "router reached at the router") in said
