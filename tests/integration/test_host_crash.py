"""Two drones' sims and bridges in one process (dronewrapper.runtime.host), and drone1's bridge
raising out of its run: drone1 alone goes offline, everything else carries on.

The host runs four members on one Zenoh session: drone1's and drone2's simulated Iris, drone1's
bridge (tests/crashing_bridge.py: the real bridge, raising once a file appears) and drone2's
bridge. After the crash drone1's liveliness token is gone and its bridge publishes no pose,
while its sim (a sibling in the same process) still runs and drone2 still takes off, reports
fresh poses and lands through the SDK; the host process stays up.
"""

from __future__ import annotations

import pytest

from dronewrapper.fleet import Fleet
from dronewrapper.msgs import registry
from dronewrapper.runtime.session import alive_services
from dronewrapper_compose.ports import free_port
from support import client_node, python_module, wait_for

pytestmark = pytest.mark.integration


def member(module: str, ns: str, name: str, endpoint: str, *args: str) -> list[str]:
    return ["-m", module, *args, "--connect", endpoint, "--namespace", ns, "--name", name]


def test_a_bridge_crashing_in_a_shared_process_takes_down_its_own_drone_only(
    router, spawn, tmp_path
):
    trigger = tmp_path / "crash"
    ports = {ns: free_port("udp") for ns in ("drone1", "drone2")}
    members = []
    for ns, port in ports.items():
        members.append(member("dronewrapper_sim", ns, "sim", router, "--scenario", "empty",
                              "--udp-onboard", f"{port}:0", "--udp-gcs", "off",
                              "--set", "cameras=false"))  # fmt: skip
    for ns, port in ports.items():
        module = "crashing_bridge" if ns == "drone1" else "dronewrapper_bridge_mavlink"
        members.append(member(module, ns, "bridge_mavlink", router,
                              "--set", f"connection=udpin:127.0.0.1:{port}"))  # fmt: skip
    argv = python_module("dronewrapper.runtime.host")
    for i, part in enumerate(members):
        argv += (["--"] if i else []) + part
    env = {"DRONEWRAPPER_TEST_CRASH_FILE": str(trigger), "PYTHONPATH": "tests"}
    host = spawn(argv, "host", env=env)
    with client_node(router, name="watcher", mode="client") as watcher:
        topic = registry.LOCAL_POSE
        poses = {ns: watcher.latest(topic, key=topic.key(ns)) for ns in ports}
        sim_truth = registry.SIM_GROUND_TRUTH
        truth = watcher.latest(sim_truth, key=sim_truth.key("drone1"))
        with Fleet.connect(connect=router, count=2, timeout=60, cameras=()) as fleet:
            assert sorted(d.name for d in fleet.online()) == ["drone1", "drone2"], host.output()
            for ns in ports:
                poses[ns].wait(10)

            trigger.touch()
            wait_for(
                lambda: "drone1/alive/bridge_mavlink" not in alive_services(watcher.session),
                15,
                what="drone1's bridge token withdrawn",
            )
            wait_for(lambda: "injected crash" in host.output(), 5, what="the crash logged")
            assert host.alive(), host.output()
            wait_for(lambda: poses["drone1"].age() > 1.0, 5, what="drone1's poses stop")
            assert truth.wait(5) is not None and truth.age() < 1.0  # its sim still runs

            drone2 = fleet["drone2"]
            drone2.takeoff(h=1.0)
            assert poses["drone2"].age() < 0.5
            assert poses["drone2"].value.pose.position.z > 0.7
            drone2.land(timeout=60)
            assert not drone2.is_flying()
            assert "drone2/alive/bridge_mavlink" in alive_services(watcher.session)
    assert host.stop(20) == 1, host.output()  # a member failed: the host says so at the end
