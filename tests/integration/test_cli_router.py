"""`dronewrapper router` and `dronewrapper alive` as real processes."""

from __future__ import annotations

import signal
import sys

import pytest

from dronewrapper.msgs import registry
from support import REPO, client_node, free_endpoint, python_module, wait_for

pytestmark = pytest.mark.integration


def test_router_process_routes_and_exits_cleanly(spawn):
    endpoint = free_endpoint()
    router = spawn(python_module("dronewrapper", "router", "--listen", endpoint), "router")
    wait_for(lambda: "listening on" in router.output(), 20, what="router start")
    toy = spawn(
        [sys.executable, str(REPO / "tests/data/toy_service.py"), "--connect", endpoint], "toy"
    )
    with client_node(endpoint) as node:
        status = node.latest(registry.CONTROLLER_STATUS)
        status.wait(20)
        alive = spawn(python_module("dronewrapper", "alive", "--connect", endpoint), "alive")
        wait_for(lambda: not alive.alive(), 20, what="alive to list and exit")
        assert alive.proc.returncode == 0
        assert "drone/alive/toy" in alive.output()
    toy.stop()
    router.proc.send_signal(signal.SIGINT)
    assert router.proc.wait(15) == 0


def test_router_on_a_busy_port_fails_clearly(spawn):
    endpoint = free_endpoint()
    first = spawn(python_module("dronewrapper", "router", "--listen", endpoint), "r1")
    wait_for(lambda: "listening on" in first.output(), 20, what="first router")
    second = spawn(python_module("dronewrapper", "router", "--listen", endpoint), "r2")
    assert second.proc.wait(30) == 1
    assert "cannot open a zenoh router session" in second.output()


def test_unknown_subcommand_and_help(spawn):
    bad = spawn(python_module("dronewrapper", "fly"), "bad")
    assert bad.proc.wait(20) == 2
    assert "unknown command 'fly'" in bad.output()
    helped = spawn(python_module("dronewrapper", "--help"), "help")
    assert helped.proc.wait(20) == 0
    assert "dronewrapper up compose/GRAPH.yaml" in helped.output()
