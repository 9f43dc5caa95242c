"""Process-graph files: a strict schema, variable substitution and validation.

A graph lists the processes that run together (in start order) and their config::

    version: 1
    description: Simulated Iris and its MAVLink bridge
    namespace: drone
    vars: {scenario: empty, onboard_port: auto, gcs_port: "14550", takeoff_height: "2.0"}
    ports: {onboard_port: udp}        # bound here: checked free; auto = a free port
    types: {gcs_port: port, takeoff_height: float}
    processes:
      - name: sim
        module: dronewrapper_sim
        args: ["--scenario", "${scenario}", "--udp-onboard", "${onboard_port}:0"]
      - name: bridge_mavlink
        module: dronewrapper_bridge_mavlink
        set: {connection: "udpin:127.0.0.1:${onboard_port}"}

``vars`` declares the graph's variables and their defaults (a ``${name:-default}`` in a process
declares ``name`` too); ``--scenario``/``--var NAME=VALUE`` on the command line override them,
and a name the graph does not declare is refused.
``types`` gives a variable's type (undeclared: ``str``): ``int``, ``float``, ``bool``
(true/false), ``port`` (1-65535, a port of another program) or a list of the allowed values;
every value, default or given, is checked against it. ``ports`` names the variables that are
ports this graph binds here (see ports.py). ``${name}`` takes a var or a built-in (``ns``,
``router``, ``repo``, ``graph_dir``, ``assets``, ``python``, ``keys``); ``${name:-default}``
falls back to ``default``. Errors name the file and the key.
"""

from __future__ import annotations

import difflib
import os
import re
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any, Literal

import msgspec

from dronewrapper.runtime.config_ranges import explain
from dronewrapper_compose import fleet

REPO = Path(__file__).resolve().parents[2]
GRAPH_DIR = Path(__file__).resolve().parents[1]  # compose/: the graph files
_VAR = re.compile(r"\$\{([A-Za-z_][A-Za-z0-9_]*)(?::-([^}]*))?\}")
_NAME = re.compile(r"[A-Za-z0-9_\-]+")


class GraphError(ValueError):
    """A graph file is malformed; the message names the file and the key."""


class ProcessSpec(msgspec.Struct, forbid_unknown_fields=True, kw_only=True):
    """One process of a graph.

    Attributes:
        name: unique in the graph; its liveliness name (ready = token ``{ns}/alive/{name}``).
        module: run as ``python -m MODULE`` (exclusive with ``command``).
        command: argv of another program (exclusive with ``module``).
        config: config file path, relative to the graph file; passed as ``--config``.
        set: config overrides, passed as ``--set KEY=VALUE``.
        args: more arguments.
        env: extra environment variables.
        ready: ``alive`` (wait for the liveliness token) or ``none`` (started is ready).
        ready_timeout_s: how long to wait for readiness, seconds.
        stop_timeout_s: how long a stop (SIGINT) may take before SIGKILL, seconds.
        zenoh_args: append the common Zenoh flags (``--connect --namespace --name --mode``).
        each_drone: run once per drone of a fleet graph of this kind (``iris``, ``tello``,
            ``any``), under the drone's namespace, all of them started together
            (:mod:`dronewrapper_compose.fleet`).
        beside: run in the process of the earlier process of this name, as a service of its
            own on the same Zenoh session (:mod:`dronewrapper.runtime.host`): a ROS 2 gateway
            beside its drone's bridge (:mod:`dronewrapper_compose.hosting`).
    """

    name: str
    module: str | None = None
    command: list[str] | None = None
    config: str | None = None
    set: dict[str, Any] = msgspec.field(default_factory=dict)
    args: list[str] = msgspec.field(default_factory=list)
    env: dict[str, str] = msgspec.field(default_factory=dict)
    ready: Literal["alive", "none"] = "alive"
    ready_timeout_s: float = 30.0
    stop_timeout_s: float = 10.0
    zenoh_args: bool = True
    each_drone: str | None = None
    beside: str | None = None


class Graph(msgspec.Struct, forbid_unknown_fields=True, kw_only=True):
    """A process graph file (``compose/NAME.yaml``)."""

    version: int
    description: str = ""
    namespace: str = "drone"
    vars: dict[str, str] = msgspec.field(default_factory=dict)
    ports: dict[str, str] = msgspec.field(default_factory=dict)  # var -> udp | tcp (ports.py)
    types: dict[str, str | list[str]] = msgspec.field(default_factory=dict)  # var -> VAR_TYPES
    processes: list[ProcessSpec]


def _is_int(value: str) -> bool:
    try:
        int(value)
    except ValueError:
        return False
    return True


def _is_float(value: str) -> bool:
    try:
        number = float(value)
    except ValueError:
        return False
    return number == number and abs(number) != float("inf")  # finite


VAR_TYPES = {  # type name -> (is the value valid, what it must be)
    "str": (lambda value: True, "text"),
    "int": (_is_int, "an integer"),
    "float": (_is_float, "a finite number"),
    "bool": (lambda value: value in ("true", "false"), "true or false"),
    "port": (lambda value: value.isdigit() and 1 <= int(value) <= 65535, "a port 1-65535"),
}


def check_value(graph: Graph, name: str, value: str) -> str | None:
    """Why ``value`` is wrong for the graph's variable ``name`` (its declared type), or None."""
    kind = graph.types.get(name, "str")
    if isinstance(kind, list):
        return None if value in kind else f"must be one of {', '.join(kind)}"
    valid, what = VAR_TYPES[kind]
    return None if valid(value) else f"must be {what}"


def declared_variables(graph: Graph) -> set[str]:
    """The variables a graph declares: its ``vars`` and each ``${name:-default}`` it uses."""
    texts: list[str] = []
    for proc in graph.processes:
        texts += [proc.module or "", proc.config or "", *(proc.command or []), *proc.args]
        texts += [str(value) for value in (*proc.set.values(), *proc.env.values())]
    defaulted = {
        m.group(1) for text in texts for m in _VAR.finditer(text) if m.group(2) is not None
    }
    return set(graph.vars) | defaulted


def parse_vars(pairs: Sequence[str]) -> dict[str, str]:
    """Graph variables from ``KEY=VALUE`` command-line pairs (GraphError for another shape)."""
    out = {}
    for pair in pairs:
        key, sep, value = pair.partition("=")
        if not sep or not key:
            raise GraphError(f"--var {pair!r} is not KEY=VALUE")
        out[key] = value
    return out


def check_variables(graph: Graph, path: Path | str, values: Mapping[str, str]) -> None:
    """Refuse a variable the graph does not declare (naming the closest declared one) or a value
    of the wrong type (naming the type).

    Raises:
        GraphError: names the file, the variable and what it must be.
    """
    declared = declared_variables(graph)
    for name, value in values.items():
        if name not in declared:
            close = difflib.get_close_matches(name, sorted(declared), n=1)
            hint = f"did you mean {close[0]}? " if close else ""
            known = ", ".join(sorted(declared)) or "none"
            raise GraphError(
                f"{path}: no variable {name!r} in this graph ({hint}declared: {known})"
            )
        if name not in graph.ports and (why := check_value(graph, name, str(value))):
            raise GraphError(f"{path}: {name}={value!r} {why}")


def _text(value: Any) -> str:
    """A YAML scalar as a variable's text (YAML's booleans as ``true``/``false``)."""
    return str(value).lower() if isinstance(value, bool) else str(value)


def assets_dir() -> Path:
    """The assets folder: ``$DRONEWRAPPER_ASSETS``, else the repository's own ``assets/``."""
    return Path(os.environ.get("DRONEWRAPPER_ASSETS", REPO / "assets"))


def substitute(text: str, values: Mapping[str, str], where: str) -> str:
    """Replace ``${name}`` / ``${name:-default}`` in ``text``; unknown names are errors."""

    def repl(m: re.Match[str]) -> str:
        name, default = m.group(1), m.group(2)
        if name in values:
            return str(values[name])
        if default is not None:
            return default
        known = ", ".join(sorted(values))
        raise GraphError(f"{where}: unknown variable ${{{name}}} (known: {known})")

    return _VAR.sub(repl, text)


def resolve_graph_path(name_or_path: str) -> Path:
    """A graph file from a path, or a bare name in compose/ (``sim_iris``)."""
    path = Path(name_or_path)
    if path.exists():
        return path
    candidate = GRAPH_DIR / f"{name_or_path.removesuffix('.yaml')}.yaml"
    if candidate.exists():
        return candidate
    names = sorted(p.stem for p in GRAPH_DIR.glob("*.yaml"))
    close = difflib.get_close_matches(Path(name_or_path).stem, names, n=1)
    hint = f"did you mean {close[0]}?" if close else f"graphs there: {', '.join(names)}"
    raise GraphError(f"{name_or_path}: no such graph file (looked in . and {GRAPH_DIR}); {hint}")


NOT_A_GRAPH = " (a graph is a YAML file such as compose/sim_iris.yaml)"


def yaml_problem(exc: Exception) -> str:
    """A YAML error in one line: what and where (line and column, 1-based)."""
    mark = getattr(exc, "problem_mark", None)
    what = getattr(exc, "problem", None) or str(exc).splitlines()[0]
    where = f"line {mark.line + 1}, column {mark.column + 1}: " if mark is not None else ""
    return f"not valid YAML at {where}{what}" if where else f"not valid YAML: {what}"


def load_graph(path: str | Path) -> Graph:
    """Read and validate a graph file.

    Raises:
        GraphError: the file is missing, not YAML, or has an unknown/missing/mistyped key, a
            duplicate process name, or a process with neither or both of module/command.
    """
    import yaml

    path = Path(path)
    try:
        raw = yaml.safe_load(path.read_text())
    except OSError as exc:
        raise GraphError(f"{path}: cannot read graph: {exc.strerror}") from exc
    except yaml.YAMLError as exc:
        raise GraphError(f"{path}: not a graph: {yaml_problem(exc)}{NOT_A_GRAPH}") from exc
    if not isinstance(raw, dict):
        raise GraphError(f"{path}: not a graph: its top level is not a mapping{NOT_A_GRAPH}")
    raw["vars"] = {k: _text(v) for k, v in (raw.get("vars") or {}).items()}
    raw["types"] = {
        k: [_text(item) for item in v] if isinstance(v, list) else v
        for k, v in (raw.get("types") or {}).items()
    }
    try:
        graph = msgspec.convert(raw, Graph)
    except msgspec.ValidationError as exc:
        raise GraphError(f"{path}: {explain(Graph, raw, exc) or exc}") from exc
    if graph.version != 1:
        raise GraphError(
            f"{path}: unsupported version {graph.version} (expected 1) - at `$.version`"
        )
    if not graph.processes:
        raise GraphError(f"{path}: no processes - at `$.processes`")
    for var, kind in graph.ports.items():
        if kind not in ("udp", "tcp"):
            raise GraphError(
                f"{path}: port kind must be udp or tcp, got {kind!r} - at `$.ports.{var}`"
            )
        if var not in graph.vars:
            raise GraphError(f"{path}: port {var!r} has no variable - at `$.ports.{var}`")
    for var, var_type in graph.types.items():
        at = f"at `$.types.{var}`"
        if var not in graph.vars:
            raise GraphError(f"{path}: type for {var!r}, which is not a variable - {at}")
        if var in graph.ports:
            raise GraphError(f"{path}: {var!r} is a port (ports:); it takes no type - {at}")
        if var_type == [] or (isinstance(var_type, str) and var_type not in VAR_TYPES):
            allowed = ", ".join(VAR_TYPES)
            raise GraphError(
                f"{path}: type {var_type!r} must be {allowed} or a list of values - {at}"
            )
        if why := check_value(graph, var, graph.vars[var]):
            raise GraphError(f"{path}: default {graph.vars[var]!r} {why} - at `$.vars.{var}`")
    seen: set[tuple[str, str | None]] = set()
    for i, proc in enumerate(graph.processes):
        at = f"at `$.processes[{i}]`"
        if not _NAME.fullmatch(proc.name):
            raise GraphError(f"{path}: process name {proc.name!r} must be [A-Za-z0-9_-] - {at}")
        # a name may repeat only for drones of different kinds (one sim per Iris, per Tello)
        kinds = (proc.each_drone,) if proc.each_drone in fleet.KINDS else (None, *fleet.KINDS)
        if any((proc.name, kind) in seen for kind in kinds):
            raise GraphError(f"{path}: duplicate process name {proc.name!r} - {at}")
        seen.update((proc.name, kind) for kind in kinds)
        if (proc.module is None) == (proc.command is None):
            raise GraphError(
                f"{path}: process {proc.name!r} needs exactly one of module/command - {at}"
            )
        if proc.each_drone is not None and proc.each_drone not in (*fleet.KINDS, fleet.ANY):
            raise GraphError(
                f"{path}: process {proc.name!r}: each_drone must be one of "
                f"{', '.join((*fleet.KINDS, fleet.ANY))} - {at}"
            )
        if proc.beside is not None:
            _check_beside(path, proc, graph.processes[:i], at)
    return graph


def _check_beside(path: Path | str, proc: ProcessSpec, earlier: list[ProcessSpec], at: str) -> None:
    """GraphError unless ``proc.beside`` names an earlier process it can share a process with:
    both run once (no ``each_drone``) and as modules (``python -m``), the other beside none."""
    target = next((p for p in earlier if p.name == proc.beside), None)
    if (
        target is None
        or target.beside is not None
        or None in (proc.module, target.module)
        or (proc.each_drone, target.each_drone) != (None, None)
    ):
        raise GraphError(
            f"{path}: process {proc.name!r}: beside {proc.beside!r} must name an earlier "
            f"process, run once as a module (python -m) and beside none - {at}"
        )
