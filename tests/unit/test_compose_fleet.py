"""Fleet graphs: N drones of one kind or a mixed list, each under its own namespace."""

from __future__ import annotations

import itertools

import pytest

from dronewrapper_compose import up
from dronewrapper_compose.fleet import FleetError, drones_of, load_warning, parse_kinds, plan_fleet
from dronewrapper_compose.graph import GRAPH_DIR, GraphError, load_graph
from dronewrapper_compose.launcher import Launcher

PORTS = itertools.count(40000)


def plan(**values):
    return plan_fleet(values, lambda: next(PORTS))


def test_n_drones_of_one_kind_under_numbered_namespaces():
    drones = plan(drones="3", kind="iris")
    assert [(d.i, d.ns, d.kind) for d in drones] == [
        (1, "drone1", "iris"), (2, "drone2", "iris"), (3, "drone3", "iris"),
    ]  # fmt: skip
    assert len({d.values["drone_port"] for d in drones}) == 3  # one autopilot port each


def test_a_mixed_list_is_cycled_over_the_drones():
    drones = plan(drones="5", kind="iris, tello")
    assert [d.kind for d in drones] == ["iris", "tello", "iris", "tello", "iris"]
    assert [d.ns for d in drones_of(drones, "tello")] == ["drone2", "drone4"]
    assert len(drones_of(drones, "any")) == 5
    assert [d.ns for d in plan(drones="2", ns_prefix="uav")] == ["uav1", "uav2"]


@pytest.mark.parametrize(
    ("values", "pattern"),
    [
        ({"drones": "0"}, "drones='0'"),
        ({"drones": "abc"}, "whole number"),
        ({"drones": "1000"}, "1..200"),
        ({"drones": "2", "kind": "iris,hexa"}, "unknown aircraft 'hexa'"),
        ({"drones": "2", "kind": " , "}, "kind"),
    ],
)
def test_bad_fleet_variables_name_the_variable(values, pattern):
    with pytest.raises(FleetError, match=pattern):
        plan(**values)
    with pytest.raises(FleetError):
        parse_kinds("") if "kind" in values else plan(**values)


def test_the_fleet_graph_expands_per_drone_with_processes_of_one_kind_started_together():
    launcher = Launcher.from_file(
        "sim_fleet", router="tcp/127.0.0.1:1", variables={"drones": "4", "kind": "iris,tello"}
    )
    labels = [[inst.label for inst in group] for group in launcher.groups]
    assert labels == [
        ["drone1/sim", "drone3/sim"], ["drone2/sim", "drone4/sim"],
        ["drone1/bridge_mavlink", "drone3/bridge_mavlink"],
        ["drone2/bridge_tello", "drone4/bridge_tello"],
    ]  # fmt: skip
    assert launcher.namespaces == ["drone1", "drone2", "drone3", "drone4"]
    sim1, sim3 = (launcher.argv_of(inst)[0] for inst in launcher.groups[0])
    bridge1 = launcher.argv_of(launcher.groups[2][0])[0]
    port1 = sim1[sim1.index("--udp-onboard") + 1].split(":")[0]
    assert f"connection=udpin:127.0.0.1:{port1}" in bridge1  # each bridge to its own sim
    assert port1 not in " ".join(sim3)
    assert "cameras=false" in sim1  # cameras off unless asked
    tello_bridge = launcher.argv_of(launcher.groups[3][1])[0]
    assert "tello_address=127.0.42.4" in tello_bridge and "video=on_demand" in tello_bridge


def test_a_bad_drone_count_is_a_graph_error():
    with pytest.raises(GraphError, match="drones="):
        Launcher.from_file("sim_fleet", router="tcp/127.0.0.1:1", variables={"drones": "x"})


def test_a_process_name_repeats_only_for_drones_of_different_kinds(tmp_path):
    path = tmp_path / "g.yaml"
    path.write_text(
        "version: 1\nvars: {drones: '2'}\nprocesses:\n"
        "  - {name: sim, module: m, each_drone: iris}\n"
        "  - {name: sim, module: m, each_drone: any}\n"
    )
    with pytest.raises(GraphError, match="duplicate process name 'sim'"):
        load_graph(path)
    path.write_text("version: 1\nprocesses:\n  - {name: sim, module: m, each_drone: hexa}\n")
    with pytest.raises(GraphError, match="each_drone must be one of"):
        load_graph(path)
    assert load_graph(GRAPH_DIR / "sim_fleet.yaml").processes[0].each_drone == "iris"


def test_a_classroom_lists_its_tellos_and_this_machines_address_for_each():
    drones = plan(addresses="192.168.1.11, 192.168.1.12", local_addresses="10.0.0.1,10.0.0.2")
    assert [(d.ns, d.values["address"], d.values["local"]) for d in drones] == [
        ("drone1", "192.168.1.11", "10.0.0.1"), ("drone2", "192.168.1.12", "10.0.0.2"),
    ]  # fmt: skip
    assert plan(addresses="192.168.1.11")[0].values["local"] == "0.0.0.0"
    with pytest.raises(FleetError, match="1 given for 2 addresses"):
        plan(addresses="a,b", local_addresses="c")
    with pytest.raises(FleetError, match="listed twice"):
        plan(addresses="a,a")
    launcher = Launcher.from_file(
        "classroom_tello",
        router="tcp/127.0.0.1:1",
        variables={"addresses": "127.0.43.1,127.0.43.2", "config": "sim"},
    )
    labels = [[inst.label for inst in group] for group in launcher.groups]
    assert labels == [["drone1/bridge_tello", "drone2/bridge_tello"], ["station"]]
    bridge2 = " ".join(launcher.argv_of(launcher.groups[0][1])[0])
    assert "tello_address=127.0.43.2" in bridge2 and "video=on_demand" in bridge2
    assert "config/sim.yaml" in bridge2


def test_a_fleet_beyond_what_the_cores_carry_is_said_with_the_measured_figure():
    assert load_warning(27, cores=2) is None  # 27 x 6.5 % = 1.76 of 2 cores, under 90 %
    said = load_warning(200, cores=2)
    assert said is not None
    assert "200 simulated drones take about 13.0 cores" in said
    assert "6.5% of one core each, docs/fleet.md" in said and "carry about 27" in said
    assert load_warning(200, cores=16) is None  # 13 of 16 cores


def test_up_warns_when_a_fleet_asks_more_than_the_machine_carries(capsys, monkeypatch):
    monkeypatch.setattr(up, "usable_cores", lambda: 2)
    assert up.main(["sim_fleet", "--var", "drones=200", "--check"]) == 0
    assert "warning: 200 simulated drones take about 13.0 cores" in capsys.readouterr().err
    assert up.main(["sim_fleet", "--var", "drones=3", "--check"]) == 0
    assert "warning" not in capsys.readouterr().err
