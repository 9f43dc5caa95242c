"""The secure graph as README's "Two machines" runs it: ``dronewrapper up
compose/sim_iris_secure.yaml --listen tls/... --identity drone1`` (signed MAVLink, the command
lease, a TLS listener with access control), and an SDK app connecting with an operator's
certificate flies it; plain tcp off loopback is refused with the reason."""

from __future__ import annotations

import socket

import pytest

from dronewrapper import DroneWrapper
from dronewrapper.security.keystore import KeyStore
from support import free_endpoint, free_port, python_module, wait_for

pytestmark = pytest.mark.integration


def test_secure_graph_flies_with_an_operator_certificate(spawn, tmp_path, monkeypatch):
    store = KeyStore(tmp_path / "keys")
    store.init()
    store.issue("drone1", "drone")
    store.issue("alice", "operator")
    store.new_mavlink_key()
    monkeypatch.setenv("DRONEWRAPPER_KEYS", str(store.root))
    tls = f"tls/127.0.0.1:{free_port()}"
    argv = python_module(
        "dronewrapper", "up", "compose/sim_iris_secure.yaml", "--router", free_endpoint(),
        "--listen", tls, "--identity", "drone1",
        "--var", f"onboard_port={free_port(socket.SOCK_DGRAM)}",
        "--var", f"gcs_port={free_port(socket.SOCK_DGRAM)}",
    )  # fmt: skip
    graph = spawn(argv, "secure_graph")
    wait_for(lambda: "all processes ready" in graph.output() or not graph.alive(), 90, what="graph")
    assert graph.alive(), graph.output()[-3000:]
    assert "access control on" in graph.output()
    with DroneWrapper(connect=tls, identity="alice", cameras=(), timeout=30) as drone:
        drone.takeoff(h=1.0, timeout=40)
        assert drone.get_state().commander == "alice"
        drone.land(timeout=60)
        assert not drone.is_flying()
    graph.stop()
    assert "command lease acquired: alice" in graph.output()
    assert "rejected" not in graph.output()  # every signed frame verified on both sides


def test_plain_tcp_off_loopback_is_refused(spawn):
    endpoint = f"tcp/0.0.0.0:{free_port()}"
    argv = python_module("dronewrapper", "up", "compose/sim_iris_secure.yaml", "--router", endpoint)
    proc = spawn(argv, "insecure")
    assert proc.proc.wait(60) == 1
    assert f"refusing to listen on {endpoint}" in proc.output()
    assert "--insecure" in proc.output()
