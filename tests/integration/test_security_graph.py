"""The secure graph as README's "Two machines" runs it: ``dronewrapper up
compose/sim_iris_secure.yaml --listen tls/... --identity drone1`` (signed MAVLink, the command
lease, a TLS listener with access control), and an SDK app connecting with an operator's
certificate flies it; plain tcp off loopback is refused with the reason."""

from __future__ import annotations

import socket

import pytest
from key_store import issued_store

from dronewrapper import DroneWrapper
from dronewrapper.errors import CommandRefused, NotConnected
from dronewrapper.security.keystore import KeyStore
from support import free_endpoint, free_port, python_module, wait_for

pytestmark = pytest.mark.integration


def test_secure_graph_flies_with_an_operator_certificate(spawn, tmp_path, monkeypatch):
    roles = {"drone1": "drone", "alice": "operator", "olga": "observer"}
    store = issued_store(tmp_path / "keys", roles)
    other = KeyStore(tmp_path / "other")
    other.init()
    other.issue("mallory", "operator")
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
    # an observer's certificate says so: its command is refused at once, never sent
    with DroneWrapper(connect=tls, identity="olga", cameras=(), timeout=30) as watcher:
        assert watcher.get_state().connected  # it may watch
        with pytest.raises(
            CommandRefused, match=r"role observer .*as its certificate says.*not sent"
        ):
            watcher.arm()
    # another CA's certificate: the client says which side refused, the router what it means
    with pytest.raises(NotConnected, match=r"TLS handshake with .* refused by this client"):
        DroneWrapper(connect=tls, identity=str(other.cert("mallory")), cameras=(), timeout=10)
    graph.stop()
    assert "command lease acquired: alice" in graph.output()
    assert "rejected TLS handshake: a client refused this router's certificate" in graph.output()
    assert "open file limit" not in graph.output()
    signing = [line for line in graph.output().splitlines() if "rejected TLS" not in line]
    assert not any("rejected" in line for line in signing)  # every signed frame verified


def test_plain_tcp_off_loopback_is_refused(spawn):
    endpoint = f"tcp/0.0.0.0:{free_port()}"
    argv = python_module("dronewrapper", "up", "compose/sim_iris_secure.yaml", "--router", endpoint)
    proc = spawn(argv, "insecure")
    assert proc.proc.wait(60) == 1
    assert f"refusing to listen on {endpoint}" in proc.output()
    assert "--insecure" in proc.output()
