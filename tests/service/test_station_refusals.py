"""The station shows beside its buttons what the bridge refused of its own commands: the drone's
snapshot carries the refusals addressed to the station's commander (the page lists them under
the command buttons and logs them), on the fake bus in bus time (see station_rig)."""

from __future__ import annotations

import pytest
from station_rig import StationRig

from dronewrapper.msgs import registry
from dronewrapper.msgs.refusal import Refusal
from dronewrapper.msgs.std import Header
from dronewrapper.runtime.fake import FakeNode

pytestmark = pytest.mark.timeout(60)


def test_the_stations_refused_setpoints_are_in_its_drones_snapshot():
    rig = StationRig()
    try:
        bridge = FakeNode("bridge_refusals", rig.bus).publisher(registry.REFUSAL)
        station = rig.link.drone.commander
        assert rig.http("GET", "/api/drones/drone")[1]["refusals"] == []
        bridge.put(Refusal(commander="someone_else", kind="lease", message="not the station's"))
        bridge.put(
            Refusal(
                header=Header(stamp=rig.bus.clock.time()),
                commander=station,
                kind="envelope",
                limit="fence",
                message="position (30, 0) m outside the envelope's fence",
                count=3,
            )
        )
        (shown,) = rig.http("GET", "/api/drones/drone")[1]["refusals"]
        assert (shown["kind"], shown["limit"], shown["count"]) == ("envelope", "fence", 3)
        assert shown["text"] == (
            "setpoint refused (envelope, fence) (x3): position (30, 0) m outside the "
            "envelope's fence"
        )
    finally:
        rig.close()
