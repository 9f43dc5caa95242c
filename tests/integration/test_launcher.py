"""`dronewrapper up` with real processes: order, readiness, log prefixes, clean stop, failures."""

from __future__ import annotations

import re
import signal
from pathlib import Path

import pytest

from support import REPO, free_endpoint, python_module, wait_for

pytestmark = pytest.mark.integration
TOYS = str(REPO / "tests" / "data" / "graph_toys.yaml")
STUBBORN = str(REPO / "tests" / "data" / "graph_toys_stubborn.yaml")


def up(*args: str) -> list[str]:
    return python_module("dronewrapper", "up", *args, "--router", free_endpoint())


def test_runs_for_duration_and_stops_cleanly(spawn):
    proc = spawn(up(TOYS, "--duration", "3"), "up")
    assert proc.proc.wait(60) == 0, proc.output()
    out = proc.output()
    assert re.search(r"^ *first \| .*toy up", out, re.M), out
    assert re.search(r"^ *second \| .*toy stopped", out, re.M), out
    assert out.index("first ready") < out.index("starting second")
    assert out.index("second | ") < out.rindex("first | ")  # reverse stop order: first stops last
    assert "all processes ready" in out and "stopped with failures" not in out


def test_ctrl_c_stops_every_process(spawn):
    proc = spawn(up(TOYS), "up")
    wait_for(lambda: "all processes ready" in proc.output(), 60, what="graph ready")
    proc.proc.send_signal(signal.SIGINT)
    assert proc.proc.wait(60) == 0, proc.output()
    assert proc.output().count("toy stopped") == 2


def children_of(pid: int) -> list[int]:
    """Live (not zombie) processes whose parent is ``pid``."""
    found = []
    for stat in Path("/proc").glob("[0-9]*/stat"):
        try:
            fields = stat.read_text().rsplit(")", 1)[1].split()
        except OSError:
            continue
        if int(fields[1]) == pid and fields[0] != "Z":
            found.append(int(stat.parent.name))
    return found


def alive(pid: int) -> bool:
    try:
        return Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0] != "Z"
    except OSError:
        return False


def test_a_killed_launcher_leaves_no_process_behind(spawn):
    """SIGKILL gives the launcher no chance to stop its graph: Linux signals the children."""
    proc = spawn(up(TOYS), "up")
    wait_for(lambda: "all processes ready" in proc.output(), 60, what="graph ready")
    children = children_of(proc.proc.pid)
    assert len(children) == 2, children
    proc.proc.kill()
    proc.proc.wait(10)
    wait_for(lambda: not any(alive(pid) for pid in children), 30, what="children gone")


def test_a_process_dying_fails_the_graph(spawn):
    proc = spawn(up(TOYS, "--var", "die_after=1"), "up")
    assert proc.proc.wait(60) == 1, proc.output()
    assert "second exited unexpectedly with code 3" in proc.output()


def test_readiness_timeout_fails_the_graph(spawn):
    proc = spawn(up(STUBBORN, "--var", "announce=false"), "up")
    assert proc.proc.wait(60) == 1, proc.output()
    assert "shy not ready after 3 s (no liveliness token toyns/alive/shy)" in proc.output()


def test_a_process_ignoring_sigint_is_killed_and_reported(spawn, tmp_path):
    # the stubborn graph, with a readiness bound a loaded machine cannot miss (3 s is there for
    # the readiness-timeout test; starting Python + Zenoh can take longer under load)
    data = REPO / "tests" / "data"
    graph = tmp_path / "stubborn.yaml"
    text = Path(STUBBORN).read_text()
    assert "ready_timeout_s: 3\n" in text
    text = text.replace("ready_timeout_s: 3\n", "ready_timeout_s: 60\n")
    graph.write_text(text.replace("${graph_dir}", str(data)))
    proc = spawn(up(str(graph), "--duration", "2"), "up")
    assert proc.proc.wait(60) == 1, proc.output()
    assert "stubborn ignored SIGINT for 1 s" in proc.output()


def test_bad_graph_exits_2_naming_file_and_key(spawn, tmp_path):
    bad = tmp_path / "bad.yaml"
    bad.write_text("version: 1\nprocesses:\n  - {name: a, module: m, restart: always}\n")
    proc = spawn(up(str(bad)), "up")
    assert proc.proc.wait(30) == 2
    assert re.search(r"bad\.yaml.*unknown field `restart`", proc.output()), proc.output()


def test_check_prints_resolved_commands(spawn):
    proc = spawn(python_module("dronewrapper", "up", "sim_iris", "--check", "--var",
                               "onboard_port=15000"), "check")  # fmt: skip
    assert proc.proc.wait(30) == 0, proc.output()
    assert "--udp-onboard 15000:0" in proc.output()
    assert "connection=udpin:127.0.0.1:15000" in proc.output()
