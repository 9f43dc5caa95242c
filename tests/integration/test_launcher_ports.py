"""`dronewrapper up` refuses a graph whose port is taken, before starting anything (two graphs
on the same UDP port would cross-talk silently), and does not mistake a port left in TIME_WAIT
for a taken one."""

from __future__ import annotations

import os
import socket

import pytest

from support import free_endpoint, python_module

pytestmark = pytest.mark.integration


def up_refused(spawn, graph: str, variable: str) -> str:
    """``dronewrapper up GRAPH --var VARIABLE`` on a free router port, which must exit 1; its
    output."""
    router = free_endpoint()
    proc = spawn(
        python_module("dronewrapper", "up", graph, "--var", variable, "--router", router), "up"
    )
    assert proc.proc.wait(60) == 1, proc.output()
    return proc.output()


def test_a_taken_autopilot_port_is_refused_with_a_clear_message(spawn):
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as held:
        held.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)  # as the bridge holds it
        held.bind(("127.0.0.1", 0))
        port = held.getsockname()[1]
        out = up_refused(spawn, "px4_sitl", f"onboard_port={port}")
    assert f"UDP port {port} (${{onboard_port}}) is already in use" in out, out
    assert "--var onboard_port=N" in out
    assert "starting bridge_mavlink" not in out  # nothing was started


def test_a_router_port_left_in_time_wait_is_free_and_a_listening_one_is_not():
    """A graph stopped while a client was connected leaves its router port in TIME_WAIT (the
    router closed first); the router binds over it, so the check must too."""
    from dronewrapper_compose.ports import port_in_use

    with socket.socket() as server:
        server.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)  # as the router's listener
        server.bind(("127.0.0.1", 0))
        server.listen()
        port = server.getsockname()[1]
        client = socket.create_connection(("127.0.0.1", port), timeout=5)
        conn, _ = server.accept()
        assert port_in_use("tcp", port)  # listening: taken
        conn.close()  # the router's side closes first: TIME_WAIT on the router's port
        client.recv(1)  # the end of stream, so the close above is complete
        client.close()
    with socket.socket() as probe, pytest.raises(OSError):  # TIME_WAIT refuses a plain bind
        probe.bind(("127.0.0.1", port))
    assert not port_in_use("tcp", port)


def test_a_tello_graph_on_a_taken_address_refuses_to_start(spawn):
    """The Tello's ports are fixed by its protocol (8889): a second simulated Tello on the
    same address fails at its bind, before its bridge starts, and says why."""
    address = f"127.0.0.{100 + os.getpid() % 100}"  # a loopback address of this test's own
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as held:
        held.bind((address, 8889))  # as the first Tello graph's simulator holds it
        out = up_refused(spawn, "sim_tello", f"address={address}")
    assert f"cannot bind udp {address}:8889" in out and "Address already in use" in out, out
    assert "start failed: sim exited with code 1 before it was ready" in out
    assert "starting bridge_tello" not in out
