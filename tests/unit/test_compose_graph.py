"""Graph files: every shipped graph validates; bad graphs fail naming the file and the key."""

from __future__ import annotations

from pathlib import Path

import pytest

from dronewrapper_compose.graph import (
    GRAPH_DIR,
    GraphError,
    check_variables,
    load_graph,
    substitute,
)
from dronewrapper_compose.launcher import Launcher, build_argv
from dronewrapper_compose.up import main as launcher_main

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
        for one in inst.members or (inst,):  # a host process: each of its services
            argv, _ = launcher.argv_of(one)
            assert argv[-8:] == [
                "--connect", "tcp/127.0.0.1:1", "--namespace", one.ns,
                "--name", one.spec.name, "--mode", "peer",
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
        (
            "version: 1\ntypes: {n: int}\nprocesses:\n  - {name: a, module: m}\n",
            r"type for 'n', which is not a variable - at `\$\.types\.n`",
        ),
        (
            "version: 1\nvars: {n: '1'}\ntypes: {n: number}\n"
            "processes:\n  - {name: a, module: m}\n",
            r"type 'number' must be str, int, float, bool, port or a list",
        ),
        (
            "version: 1\nvars: {n: x}\ntypes: {n: int}\nprocesses:\n  - {name: a, module: m}\n",
            r"default 'x' must be an integer - at `\$\.vars\.n`",
        ),
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


TYPED = """version: 1
vars: {gcs_port: "14550", scenario: empty, height: "2.0", on_exit: land, video: "false", n: "2"}
types: {gcs_port: port, height: float, on_exit: [land, stop], video: bool, n: int}
processes:
  - {name: a, module: m}
"""


@pytest.mark.parametrize(
    ("values", "pattern"),
    [
        ({"gcs_port": "abc"}, r"gcs_port='abc' must be a port 1-65535"),
        ({"gcs_port": "0"}, r"gcs_port='0' must be a port"),
        ({"height": "nan"}, r"height='nan' must be a finite number"),
        ({"on_exit": "hover"}, r"on_exit='hover' must be one of land, stop"),
        ({"video": "yes"}, r"video='yes' must be true or false"),
        ({"n": "2.5"}, r"n='2.5' must be an integer"),
        ({"scenaro": "x"}, r"no variable 'scenaro' in this graph \(did you mean scenario\? "),
    ],
)
def test_command_line_variables_are_checked_against_the_declared_names_and_types(
    tmp_path, values, pattern
):
    path = write(tmp_path, TYPED)
    with pytest.raises(GraphError, match=pattern):
        check_variables(load_graph(path), path, values)
    good = {"gcs_port": "14551", "scenario": "x", "height": "1.5", "on_exit": "stop", "n": "3"}
    check_variables(load_graph(path), path, {**good, "video": "true"})  # all fine


def test_a_variable_with_an_inline_default_is_declared(tmp_path):
    path = write(tmp_path, "version: 1\nprocesses:\n  - {name: a, module: m, args: ['${n:-1}']}\n")
    check_variables(load_graph(path), path, {"n": "2"})
    with pytest.raises(GraphError, match=r"no variable 'm' in this graph \(declared: n\)"):
        check_variables(load_graph(path), path, {"m": "2"})


def test_the_launcher_checks_every_typed_value_wherever_it_came_from(tmp_path):
    path = write(tmp_path, TYPED)
    with pytest.raises(GraphError, match=r"gcs_port='abc' must be a port"):
        Launcher.from_file(path, router="tcp/127.0.0.1:1", variables={"gcs_port": "abc"})


@pytest.mark.parametrize(
    ("argv", "said"),
    [
        (["--var", "gcs_port=abc"], "gcs_port='abc' must be a port 1-65535"),
        (["--var", "scenaro=x"], "no variable 'scenaro' in this graph (did you mean scenario?"),
        (["--var", "on_exit=hover"], "on_exit='hover' must be one of land, stop"),
    ],
)
def test_up_refuses_a_bad_var_before_starting_anything(capsys, argv, said):
    assert launcher_main(["sim_follow_color", "--check", *argv]) == 2
    assert said in capsys.readouterr().err


@pytest.mark.parametrize("path", SHIPPED, ids=lambda p: p.stem)
def test_every_shipped_variable_that_is_not_text_is_typed(path: Path):
    """A number, a boolean or a port left as text would let ``--var x=abc`` through."""
    graph = load_graph(path)
    for name, default in graph.vars.items():
        if name in graph.ports:
            continue
        looks_typed = default in ("true", "false") or _number(default) or name.endswith("_port")
        assert not looks_typed or name in graph.types, f"{path.name}: {name} has no type"


def _number(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


@pytest.mark.parametrize(
    ("graph", "said"),
    [
        ("sim_irs", "sim_irs: no such graph file"),
        ("sim_irs", "did you mean sim_iris?"),
        ("compose/sim_follow_colour.yaml", "did you mean sim_follow_color?"),
        ("README.md", "README.md: not a graph: not valid YAML at line "),
    ],
)
def test_up_names_the_file_and_the_closest_graph(capsys, monkeypatch, graph, said):
    monkeypatch.chdir(GRAPH_DIR.parent)
    assert launcher_main([graph, "--check"]) == 2
    err = capsys.readouterr().err
    assert said in err and err.count("\n") == 1, err  # one line, no YAML traceback text


def test_a_file_that_is_yaml_but_not_a_mapping_is_not_a_graph(tmp_path):
    with pytest.raises(GraphError, match=r"g\.yaml: not a graph: its top level is not a mapping"):
        load_graph(write(tmp_path, "- a\n- b\n"))
