"""A fleet graph's ``per_process``: N drones' sims and bridges packed into one host process
(dronewrapper_compose.hosting), a process ``beside`` another in its process, and the host's
command line (dronewrapper.runtime.host)."""

from __future__ import annotations

import sys

import pytest

from dronewrapper.runtime.host import split_members
from dronewrapper_compose.graph import GraphError
from dronewrapper_compose.launcher import Launcher


def fleet(**variables: str) -> Launcher:
    return Launcher.from_file("sim_fleet", router="tcp/127.0.0.1:1", variables=variables)


def test_per_process_packs_n_drones_sims_and_bridges_into_each_host():
    launcher = fleet(drones="7", per_process="3")
    assert [[inst.label for inst in group] for group in launcher.groups] == [
        ["drone1-drone3/host", "drone4-drone6/host", "drone7/host"]
    ]
    first = launcher.groups[0][0]
    assert [m.label for m in first.members] == [
        "drone1/sim",
        "drone2/sim",
        "drone3/sim",
        "drone1/bridge_mavlink",
        "drone2/bridge_mavlink",
        "drone3/bridge_mavlink",
    ]  # fmt: skip every sim, then every bridge: each drone's started as without hosting
    assert first.tokens() == [(m.ns, m.spec.name) for m in first.members]  # ready: all six
    assert launcher.namespaces == [f"drone{i}" for i in range(1, 8)]


def test_a_hosts_command_line_is_its_members_command_lines_joined():
    launcher = fleet(drones="2", per_process="2")
    host = launcher.groups[0][0]
    argv, _ = launcher.argv_of(host)
    assert argv[:3] == [sys.executable, "-m", "dronewrapper.runtime.host"]
    members = split_members(argv[3:])
    assert [module for module, _ in members] == [
        "dronewrapper_sim", "dronewrapper_sim",
        "dronewrapper_bridge_mavlink", "dronewrapper_bridge_mavlink",
    ]  # fmt: skip
    for (module, args), member in zip(members, host.members, strict=True):
        assert [sys.executable, "-m", module, *args] == launcher.argv_of(member)[0]
    sim1, bridge1 = members[0][1], members[2][1]
    port = sim1[sim1.index("--udp-onboard") + 1].split(":")[0]
    assert f"connection=udpin:127.0.0.1:{port}" in bridge1  # still each bridge to its own sim


def test_per_process_1_keeps_a_process_per_drone_and_program():
    labels = [[inst.label for inst in group] for group in fleet(drones="2").groups]
    assert labels == [["drone1/sim", "drone2/sim"],
                      ["drone1/bridge_mavlink", "drone2/bridge_mavlink"]]  # fmt: skip


@pytest.mark.parametrize("value", ["0", "-1", "two"])
def test_a_bad_per_process_is_a_graph_error(value):
    with pytest.raises(GraphError, match="per_process"):
        fleet(drones="2", per_process=value)


@pytest.mark.parametrize("argv", [[], ["x"], ["-m"], ["-m", "a", "--", "b"]])
def test_each_hosted_member_starts_with_dash_m_module(argv):
    with pytest.raises(ValueError, match="-m MODULE"):
        split_members(argv)


def test_a_process_beside_another_runs_in_its_process_as_a_service_of_its_own():
    launcher = Launcher.from_file("sim_iris_ros2_hosted", router="tcp/127.0.0.1:1")
    assert [[inst.label for inst in group] for group in launcher.groups] == [
        ["sim"],
        ["bridge_mavlink+ros2_gateway"],
    ]
    host = launcher.groups[1][0]
    assert host.tokens() == [("drone", "bridge_mavlink"), ("drone", "ros2_gateway")]
    argv, _ = launcher.argv_of(host)
    assert argv[:3] == [sys.executable, "-m", "dronewrapper.runtime.host"]
    members = split_members(argv[3:])
    assert [module for module, _ in members] == [
        "dronewrapper_bridge_mavlink",
        "dronewrapper_ros2_gateway",
    ]
    assert "domain_id=0" in members[1][1]  # each its own config
    assert not any(arg.startswith("ros2.") for arg in members[0][1])


@pytest.mark.parametrize(
    "beside", ["nowhere", "gateway", "sim_fleet_member"], ids=["unknown", "later", "each_drone"]
)
def test_beside_names_an_earlier_process_run_once(tmp_path, beside):
    graph = tmp_path / "g.yaml"
    graph.write_text(
        "version: 1\nprocesses:\n"
        "  - {name: sim_fleet_member, module: dronewrapper_sim, each_drone: any}\n"
        "  - {name: bridge, module: dronewrapper_bridge_mavlink}\n"
        f"  - {{name: gw, module: dronewrapper_ros2_gateway, beside: {beside}}}\n"
        "  - {name: gateway, module: dronewrapper_ros2_gateway}\n"
    )
    with pytest.raises(GraphError, match=rf"beside {beside!r} must name an earlier process"):
        Launcher.from_file(graph, router="tcp/127.0.0.1:1")
