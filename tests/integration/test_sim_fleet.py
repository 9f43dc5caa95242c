"""The fleet graph with five drones of two kinds on one router, flown as one fleet by the SDK.

Wiring only: each drone's sim and bridge come up under its own namespace, the fleet finds all
five with their kinds, and a take-off and a landing ordered to all reach each drone (its own
ground truth climbs, and only its own), and an Iris reset to its start is on the ground,
disarmed, while the others fly on. The fleet's logic is tested on the fake bus
(tests/service/test_sdk_fleet.py); the graph's expansion in tests/unit/test_compose_fleet.py.
"""

from __future__ import annotations

import io

import pytest

from dronewrapper.fleet import Fleet
from dronewrapper.msgs import registry
from dronewrapper.msgs.simulation import VehicleReset
from dronewrapper_compose.launcher import Launcher
from support import client_node, free_endpoint, wait_for

pytestmark = pytest.mark.integration

NAMES = [f"drone{i}" for i in range(1, 6)]


def test_five_drones_of_two_kinds_take_off_and_land_together():
    endpoint, log = free_endpoint(), io.StringIO()
    variables = {"drones": "5", "kind": "iris,tello"}
    with Launcher.from_file("sim_fleet", router=endpoint, variables=variables, out=log) as graph:
        assert sorted(graph.namespaces) == sorted(NAMES)
        with client_node(endpoint, name="truth", mode="client") as watcher:
            topic = registry.SIM_GROUND_TRUTH
            truth = {ns: watcher.latest(topic, key=topic.key(ns)) for ns in NAMES}
            with Fleet.connect(connect=endpoint, count=5, timeout=60, cameras=()) as fleet:
                infos = {info.name: info for info in fleet.online()}
                assert list(infos) == NAMES, log.getvalue()
                kinds = [infos[ns].kind for ns in NAMES]
                assert kinds == ["px4", "tello", "px4", "tello", "px4"]
                assert all(info.connected for info in infos.values())

                # only drone2 and drone3 take off: the command reaches the right drones
                fleet.each(lambda d: d.takeoff(h=1.0), ["drone2", "drone3"]).raise_errors()
                heights = {ns: truth[ns].wait(10).pose.position.z for ns in NAMES}
                assert heights["drone2"] > 0.5 and heights["drone3"] > 0.8, heights
                assert all(heights[ns] < 0.2 for ns in ("drone1", "drone4", "drone5")), heights

                # drone3 (an Iris) is reset to its start: on the ground, disarmed, at once
                reply = watcher.call(registry.SIM_RESET, VehicleReset(), ns="drone3", timeout=10)
                assert reply.success, reply
                wait_for(lambda: truth["drone3"].value.pose.position.z < 0.05, 10, what="reset")
                wait_for(lambda: not fleet["drone3"].get_state().armed, 10, what="disarmed")
                assert truth["drone2"].wait(5).pose.position.z > 0.5  # the other one flies on

                result = fleet.land(timeout=60, names=["drone2"])
                assert result.ok, result.failed
                assert not any(d.is_flying() for d in fleet)
    assert graph.exit_code == 0, log.getvalue()
