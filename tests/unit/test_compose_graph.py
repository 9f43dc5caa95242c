"""Graph files: every shipped graph validates; bad graphs fail naming the file and the key."""

from __future__ import annotations

from pathlib import Path

import pytest

from dronewrapper_compose.graph import GRAPH_DIR, GraphError, load_graph, substitute
from dronewrapper_compose.launcher import Launcher, build_argv

SHIPPED = sorted(GRAPH_DIR.glob("*.yaml"))
FIXED_NAMES = ["sim_iris", "px4_sitl", "ardupilot_sitl"]


def test_fixed_graph_names_exist():
    names = {p.stem for p in SHIPPED}
    assert set(FIXED_NAMES) <= names


@pytest.mark.parametrize("path", SHIPPED, ids=lambda p: p.stem)
def test_shipped_graphs_validate_and_resolve(path: Path):
    launcher = Launcher.from_file(path, router="tcp/127.0.0.1:1")
    for inst in (inst for group in launcher.groups for inst in group):
        argv, _ = launcher.argv_of(inst)
        assert "${" not in " ".join(argv), argv
        assert argv[-8:] == [
            "--connect", "tcp/127.0.0.1:1", "--namespace", inst.ns,
            "--name", inst.spec.name, "--mode", "peer",
        ]  # fmt: skip


def write(tmp_path, text: str) -> Path:
    path = tmp_path / "g.yaml"
    path.write_text(text)
    return path


@pytest.mark.parametrize(
    ("text", "pattern"),
    [
        ("version: 1\nprocesses:\n  - name: a\n    modul: x\n", r"g\.yaml.*unknown field `modul`"),
        ("version: 1\nprocesses:\n  - name: a\n", r"g\.yaml.*exactly one of module/command"),
        ("version: 2\nprocesses:\n  - {name: a, module: m}\n", r"g\.yaml.*version"),
        (
            "version: 1\nprocesses:\n  - {name: a, module: m}\n  - {name: a, module: m}\n",
            r"g\.yaml.*duplicate process name 'a'",
        ),
        ("version: 1\nprocesses: []\n", r"no processes"),
        ("version: 1\nprocesses:\n  - {name: 'a b', module: m}\n", r"process name"),
        ("version: 1\nprocesses:\n  - {name: a, module: m, ready: maybe}\n", r"ready"),
        ("processes:\n  - {name: a, module: m}\n", r"missing required field `version`"),
    ],
)
def test_bad_graphs(tmp_path, text, pattern):
    with pytest.raises(GraphError, match=pattern):
        load_graph(write(tmp_path, text))


def test_substitution():
    assert substitute("${a}-${b:-x}", {"a": "1"}, "w") == "1-x"
    with pytest.raises(GraphError, match=r"w: unknown variable \$\{c\}"):
        substitute("${c}", {"a": "1"}, "w")


def test_unknown_variable_in_a_process_is_named(tmp_path):
    path = write(tmp_path, "version: 1\nprocesses:\n  - {name: a, module: m, args: ['${nope}']}\n")
    launcher = Launcher.from_file(path, router="tcp/127.0.0.1:1")
    with pytest.raises(GraphError, match=r"process 'a'.*\$\{nope\}"):
        build_argv(launcher.graph.processes[0], launcher.values, path, "drone", "x")


def test_missing_config_file_is_named(tmp_path):
    path = write(tmp_path, "version: 1\nprocesses:\n  - {name: a, module: m, config: none.yaml}\n")
    launcher = Launcher.from_file(path, router="tcp/127.0.0.1:1")
    with pytest.raises(GraphError, match=r"none\.yaml does not exist"):
        build_argv(launcher.graph.processes[0], launcher.values, path, "drone", "x")
