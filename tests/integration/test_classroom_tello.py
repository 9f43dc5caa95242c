"""A classroom of three simulated Tellos: compose/classroom_tello.yaml serves them (one bridge
each and the ground station) the way it serves real ones, each simulated Tello on an address
of its own (127.0.43.1-3, as Tellos in station mode on one access point).

Wiring only: the station lists all three; the SDK's fleet takes them all off; the station's
"land all" lands every one; the station resets one of them to its start while the others stay
where they are. The logic is tested on the fake bus (tests/service/test_station_fleet.py,
tests/service/test_sdk_fleet.py, tests/unit/test_sim_reset.py).
"""

from __future__ import annotations

import io
import json
import urllib.request

import pytest

from dronewrapper.fleet import Fleet
from dronewrapper.msgs import registry
from dronewrapper.msgs.mavros import LANDED_STATE_ON_GROUND
from dronewrapper_compose.launcher import Launcher
from support import client_node, free_endpoint, free_port, python_module, wait_for

pytestmark = pytest.mark.integration

NAMES = ["drone1", "drone2", "drone3"]
ADDRESSES = [f"127.0.43.{i}" for i in range(1, 4)]


def call(url: str, method: str = "GET") -> tuple[int, dict]:
    request = urllib.request.Request(url, method=method, data=b"{}" if method == "POST" else None)
    request.add_header("Content-Type", "application/json")
    try:
        with urllib.request.urlopen(request, timeout=90) as reply:
            return reply.status, json.loads(reply.read())
    except urllib.error.HTTPError as exc:
        return exc.code, json.loads(exc.read())


def test_a_classroom_of_three_simulated_tellos(spawn):
    endpoint, port, log = free_endpoint(), free_port(), io.StringIO()
    variables = {
        "addresses": ",".join(ADDRESSES),
        "local_addresses": ",".join(ADDRESSES),  # a simulated Tello answers on its own address
        "config": "sim",
        "station_port": str(port),
    }
    with Launcher.from_file("classroom_tello", router=endpoint, variables=variables, out=log):
        for ns, address in zip(NAMES, ADDRESSES, strict=True):  # the Tellos are switched on
            spawn(python_module("dronewrapper_sim", "--aircraft", "tello", "--scenario", "empty",
                                "--address", address, "--connect", endpoint, "--namespace", ns,
                                "--name", "sim"), f"tello_{ns}")  # fmt: skip
        station = f"http://127.0.0.1:{port}"
        wait_for(
            lambda: [d["health"] for d in call(f"{station}/api/drones")[1]] == ["ok"] * 3,
            60,
            what="the station showing three healthy Tellos",
        )
        with client_node(endpoint, name="truth", mode="client") as watcher:
            topic = registry.SIM_GROUND_TRUTH
            truth = {ns: watcher.latest(topic, key=topic.key(ns)) for ns in NAMES}
            with Fleet.connect(connect=endpoint, count=3, timeout=60, cameras=()) as fleet:
                assert [info.kind for info in fleet.online()] == ["tello"] * 3
                fleet.takeoff(h=1.0).raise_errors()
                status, reply = call(f"{station}/api/fleet/land", "POST")
                assert status == 200 and reply == {"ok": True, "drones": dict.fromkeys(
                    NAMES, "landed")}, reply  # fmt: skip
                assert not any(drone.is_flying() for drone in fleet)

                fleet.each(lambda d: d.takeoff(h=1.0), ["drone2", "drone3"]).raise_errors()
                status, reply = call(f"{station}/api/drones/drone2/reset", "POST")
                assert status == 200 and reply["ok"], reply
                wait_for(lambda: truth["drone2"].value.pose.position.z < 0.05, 10, what="reset")
                assert truth["drone3"].wait(5).pose.position.z > 0.5  # the others fly on
                fleet["drone2"].wait_for_landed_state(LANDED_STATE_ON_GROUND, 10)  # the bridge too
                fleet.land(names=["drone3"]).raise_errors()
