"""`dronewrapper router` and `dronewrapper alive` as real processes."""

from __future__ import annotations

import signal
import subprocess
import sys
import threading

import pytest

from dronewrapper.msgs import registry
from dronewrapper.msgs.mavros import State
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


def test_version_and_key_hints(spawn):
    version = spawn(python_module("dronewrapper", "--version"), "version")
    assert version.proc.wait(20) == 0
    assert version.output().startswith("dronewrapper ")
    slash = spawn(python_module("dronewrapper", "echo", "/drone/mavros/state"), "slash")
    assert slash.proc.wait(20) == 2
    assert "no leading '/': try 'drone/mavros/state'" in slash.output()


def test_zenoh_errors_are_one_line_without_source_paths(spawn):
    bad = spawn(python_module("dronewrapper", "router", "--listen", "tcp/192.0.2.1:9"), "bad")
    assert bad.proc.wait(30) == 1
    lines = bad.output().strip().splitlines()
    assert len(lines) == 1 and ".rs:" not in lines[0], lines


def test_echo_into_a_closed_pipe_exits_quietly_and_silence_is_explained(router, spawn):
    """`dronewrapper echo KEY | head -n 1` ends with status 0 and no traceback; a key that
    nobody publishes is reported with what is published nearby."""
    with client_node(router) as node:
        state = node.publisher(registry.STATE)
        stop = threading.Event()

        def publish() -> None:
            while not stop.wait(0.05):
                state.put(State(connected=True, mode="OFFBOARD"))

        thread = threading.Thread(target=publish, daemon=True)
        thread.start()
        try:
            pipeline = subprocess.run(
                f"{sys.executable} -m dronewrapper echo drone/mavros/state --connect {router}"
                " | head -n 1",
                shell=True,
                capture_output=True,
                text=True,
                timeout=60,
                executable="/bin/bash",
            )
            assert pipeline.stdout.startswith("drone/mavros/state [State]")
            assert "Traceback" not in pipeline.stderr and "BrokenPipe" not in pipeline.stderr

            quiet = spawn(
                python_module(
                    "dronewrapper",
                    "echo",
                    "drone/mavros/sate",
                    "--connect",
                    router,
                    "--duration",
                    "8",
                ),
                "quiet",
            )
            wait_for(lambda: "nothing received" in quiet.output(), 30, what="silence notice")
            wait_for(lambda: not quiet.alive(), 30, what="echo to end")
            assert "published nearby: drone/mavros/state" in quiet.output()
        finally:
            stop.set()
            thread.join(2)


def test_usage_lines_name_the_real_command_and_help_lists_scenarios(spawn):
    sim = spawn(python_module("dronewrapper", "sim", "--help"), "sim-help")
    assert sim.proc.wait(30) == 0
    assert sim.output().startswith("usage: dronewrapper sim ")
    assert "people_crossing_front" in sim.output() and "beacon_abrupt" in sim.output()
    bridge = spawn(python_module("dronewrapper_bridge_mavlink", "--help"), "bridge-help")
    assert bridge.proc.wait(30) == 0
    assert bridge.output().startswith("usage: python -m dronewrapper_bridge_mavlink ")


@pytest.mark.parametrize(
    "command",
    [
        ["echo", "drone/**"],
        ["alive"],
        ["record", "drone/**", "-o", "{tmp}/never.mcap"],
        ["up", "sim_iris", "--use-router", "--router", "{endpoint}"],
    ],
    ids=lambda c: c[0] if "--use-router" not in c else "up --use-router",
)
def test_with_no_router_a_command_fails_at_once_saying_what_to_do(spawn, tmp_path, command):
    """A refused connection is no router: the command says so and what to do, and never
    waits out the session's retries to print Zenoh's own error."""
    endpoint = free_endpoint()  # nothing listens here
    argv = [part.format(tmp=tmp_path, endpoint=endpoint) for part in command]
    if command[0] != "up":
        argv += ["--connect", endpoint]
    proc = spawn(python_module("dronewrapper", *argv), command[0])
    assert proc.proc.wait(30) == 1, proc.output()
    out = proc.output()
    assert f"no router at {endpoint} (connection refused)" in out, out
    assert "dronewrapper up compose/GRAPH.yaml" in out
    assert "cannot open a zenoh" not in out  # the session's retries never ran
    assert "starting sim" not in out  # up started nothing
