"""A graph's ports: taken ones are refused naming the variable, ``auto`` picks a free one."""

from __future__ import annotations

import io
import socket

import pytest

from dronewrapper_compose.graph import GRAPH_DIR, GraphError, load_graph
from dronewrapper_compose.launcher import Launcher, LaunchError
from dronewrapper_compose.ports import (
    PortInUse,
    check_ports_free,
    choose_ports,
    ephemeral_range,
    free_fixed_port,
    port_in_use,
    router_port_in_use,
)


@pytest.fixture
def bound_udp():
    """A UDP port held like the bridge holds it (udpin sets SO_REUSEADDR)."""
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as sock:
        sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        sock.bind(("127.0.0.1", 0))
        yield sock.getsockname()[1]


def test_a_reusable_udp_bind_counts_as_taken(bound_udp):
    assert port_in_use("udp", bound_udp)


def test_taken_ports_are_refused_naming_the_variable(bound_udp):
    with pytest.raises(
        PortInUse, match=rf"UDP port {bound_udp} \(\$\{{onboard_port\}}\) is already"
    ):
        check_ports_free({"onboard_port": "udp"}, {"onboard_port": str(bound_udp)})


def test_auto_picks_a_free_port_and_numbers_stay():
    chosen = choose_ports({"a": "udp", "b": "tcp"}, {"a": "auto", "b": "15000"})
    assert chosen["b"] == "15000"
    assert not port_in_use("udp", int(chosen["a"]))
    with pytest.raises(ValueError, match="must be a port number"):
        choose_ports({"a": "udp"}, {"a": "fourteen"})


def test_the_simulated_graphs_pick_free_ports_and_px4_sitl_does_not():
    for name in ("sim_iris", "sim_iris_secure", "sim_follow_color", "sim_follow_person"):
        graph = load_graph(GRAPH_DIR / f"{name}.yaml")
        assert graph.ports == {"onboard_port": "udp"} and graph.vars["onboard_port"] == "auto"
    sitl = load_graph(GRAPH_DIR / "px4_sitl.yaml")
    assert sitl.ports == {"onboard_port": "udp"} and sitl.vars["onboard_port"] == "14540"


# ``*_port`` variables that are another program's port, which this graph does not bind
PEER_PORTS = {
    "gcs_port": "the simulator sends its ground-station link there (QGroundControl binds it)",
    "sitl_port": "ArduPilot SITL's TCP server; the bridge connects to it",
    "truth_port": "ArduPilot SITL's SERIAL1 TCP server; the world connects to it for SIM_STATE",
}
# graphs whose ports are fixed by the aircraft's protocol, bound without address reuse: a second
# such graph on the same address fails at its first bind (the Tello SDK's 8889/8890/11111;
# tests/integration/test_launcher_ports.py holds it)
FIXED_BY_PROTOCOL = {"sim_tello", "sim_tello_follow_color", "sim_tello_follow_person"}
FIXED_BY_PEER = {  # the other end's port: refused if taken
    "px4_sitl": "PX4 SITL sends to 14540",
    "px4_sitl_world": "PX4 SITL sends to 14540 and its SIH truth to 19410",
    "px4_sitl_follow_color": "PX4 SITL sends to 14540 and its SIH truth to 19410",
    "px4_sitl_follow_person": "PX4 SITL sends to 14540 and its SIH truth to 19410",
    "px4_zenoh_world": "PX4 SIH sends its truth to 19410",
    "px4_zenoh_follow_color": "PX4 SIH sends its truth to 19410",
    "px4_zenoh_follow_person": "PX4 SIH sends its truth to 19410",
}
# fleet graphs: each drone's autopilot port is a free one the launcher picks per drone
# (``${drone_port}``, dronewrapper_compose.fleet), and each Tello has an address of its own
CHOSEN_PER_DRONE = {"sim_fleet"}


@pytest.mark.parametrize("path", sorted(GRAPH_DIR.glob("*.yaml")), ids=lambda p: p.stem)
def test_every_graph_picks_free_ports_or_refuses_to_start(path):
    """A port variable is either bound here (declared in ``ports:``, so checked free before
    start, and ``auto`` in every simulated graph) or named above as another program's."""
    graph = load_graph(path)
    for name in graph.vars:
        if name.endswith("_port") and name not in graph.ports:
            assert name in PEER_PORTS, f"{path.name}: {name} is neither in ports: nor a peer's"
            assert graph.types.get(name) == "port", f"{path.name}: {name} is not typed port"
    for name in graph.ports:
        if path.stem.startswith("sim_"):
            assert graph.vars[name] == "auto", f"{path.name}: {name} is fixed"
        else:
            assert path.stem in FIXED_BY_PEER or graph.vars[name] == "auto"
    if path.stem.startswith("sim_") and not graph.ports:
        assert path.stem in FIXED_BY_PROTOCOL | CHOSEN_PER_DRONE, (
            f"{path.name}: a simulated graph binds no port?"
        )


def test_two_secure_sims_get_different_ports():
    a = Launcher.from_file("sim_iris_secure", out=io.StringIO())
    b = Launcher.from_file("sim_iris_secure", out=io.StringIO())
    assert a.values["onboard_port"] != b.values["onboard_port"]


def test_two_sim_graphs_get_different_ports():
    a = Launcher.from_file("sim_iris", out=io.StringIO())
    b = Launcher.from_file("sim_iris", out=io.StringIO())
    assert a.values["onboard_port"] != b.values["onboard_port"]


def test_a_graph_whose_port_is_taken_refuses_to_start(bound_udp):
    launcher = Launcher.from_file(
        "sim_iris", variables={"onboard_port": str(bound_udp)}, out=io.StringIO()
    )
    with pytest.raises(LaunchError, match=rf"sim_iris.yaml: UDP port {bound_udp}"):
        launcher.start()
    assert launcher.children == []  # nothing was started


def test_a_taken_router_port_is_named():
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        sock.listen()
        port = sock.getsockname()[1]
        assert router_port_in_use(f"tcp/127.0.0.1:{port}") == port
    assert router_port_in_use("tcp/192.168.1.2:7447") is None


def test_a_port_without_a_variable_is_a_graph_error(tmp_path):
    bad = tmp_path / "bad.yaml"
    bad.write_text("version: 1\nports: {p: udp}\nprocesses:\n  - {name: a, module: m}\n")
    with pytest.raises(GraphError, match=r"\$\.ports\.p"):
        load_graph(bad)
    bad.write_text(
        "version: 1\nvars: {p: '1'}\nports: {p: sctp}\nprocesses:\n  - {name: a, module: m}\n"
    )
    with pytest.raises(GraphError, match="udp or tcp"):
        load_graph(bad)


def test_a_fleets_drone_port_is_free_and_outside_the_ephemeral_range():
    """No socket bound to port 0 (a simulator's link) can take a bridge's port before the
    bridge binds it: the port is below the range the kernel hands out."""
    low, _high = ephemeral_range()
    ports = {free_fixed_port("udp") for _ in range(20)}
    assert all(port < low and not port_in_use("udp", port) for port in ports)
    assert len(ports) > 1  # picked at random, not one fixed number
