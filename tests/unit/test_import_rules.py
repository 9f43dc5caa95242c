"""Which floor of the house may import which, read from the source (``ast``, no import run).

Floors from the bottom:

- the contract, ``dronewrapper.msgs`` (``contract/``: the messages, the keys and plain data
  such as the envelope): it imports nothing of ours but itself;
- the runtime, ``dronewrapper.runtime`` and ``dronewrapper.security`` (``runtime/``): it
  imports only the contract;
- the thin client a laptop installs, the rest of ``dronewrapper`` (``sdk/``);
- the tools (``tools/``: the ``dronewrapper`` command, doctor, echo, record, router, keys);
- the libraries the on-board side shares and no laptop needs: the bridges' rules
  (``dronewrapper_bridge_base``) and the ROS 2 codec (``dronewrapper_ros2_codec``);
- the services (one package each under ``services/``): a service imports no other service;
  two services that share a process do so as two ``run(node, config)`` on one session
  (``dronewrapper.runtime.host``), never by importing each other;
- the simulator, then the graphs (``dronewrapper_compose``, which names them all).

A package imports only floors below it. The four distributions of ``dronewrapper`` (contract,
runtime, client, tools) each import only those below them; the tools may name on-board packages
below the graphs (the CLI finds the stack's subcommands through entry points and names none),
and nothing below the tools names a tool, so that a laptop installs the client without them.
:data:`KNOWN` lists the imports that break a rule, each with its file: it is empty, and may
only shrink (a new break fails, and so does a listed one that is gone, so the list stays true).

Within and across floors, no import circle: :data:`KNOWN_CIRCLES`, empty too, may only shrink
the same way. A module that calls back into the object that imports it names that object
through a protocol of its own (in the bridges, the port each sibling of the core states, made
of ``dronewrapper_bridge_base.core_view``'s pieces), not by importing it.
"""

from __future__ import annotations

import ast
from collections.abc import Mapping
from functools import cache
from pathlib import Path
from typing import NamedTuple

import tomllib

REPO = Path(__file__).resolve().parents[2]
LIBRARIES = {"dronewrapper_bridge_base", "dronewrapper_ros2_codec"}
"""Packages under ``services/`` that are shared code, not services."""
PACKAGES = {f"dronewrapper_{p.parent.name}" for p in (REPO / "services").glob("*/pyproject.toml")}
SERVICE_PACKAGES = PACKAGES - LIBRARIES
SDK = {"dronewrapper", "drone_wrapper"}
CONTRACT = "dronewrapper.msgs"
COMPOSE = "dronewrapper_compose"
SDK_PARTS = ("contract", "runtime", "sdk", "tools")
"""The distributions of the ``dronewrapper`` package, each importing only those before it."""
TOOLS = "tools/"
"""The SDK's tools: the only SDK modules that may name on-board packages."""

KNOWN: set[tuple[str, str]] = set()
"""(file, imported package) pairs that break a rule (none)."""

KNOWN_CIRCLES: set[frozenset[str]] = set()
"""Circles allowed, each as its modules' dotted names (none)."""


class Import:
    """One absolute import of a source file: the module named, and whether it sits inside a
    function (run only when called) or at module level (run on import)."""

    def __init__(self, module: str, lazy: bool) -> None:
        self.module = module
        self.lazy = lazy

    @property
    def package(self) -> str:
        return self.module.split(".")[0]


def imports_of(path: Path) -> list[Import]:
    """Every absolute import of ``path`` (``from X import y`` names X.y: y may be a module,
    else it is a name in X). Imports are statements: only statement bodies are walked."""
    found: list[Import] = []

    def visit(body: list[ast.stmt], lazy: bool) -> None:
        for statement in body:
            if isinstance(statement, ast.Import):
                found.extend(Import(alias.name, lazy) for alias in statement.names)
            elif isinstance(statement, ast.ImportFrom) and statement.level == 0:
                module = statement.module or ""
                found.extend(Import(f"{module}.{a.name}", lazy) for a in statement.names)
            inner = lazy or isinstance(statement, ast.FunctionDef | ast.AsyncFunctionDef)
            for field in ("body", "orelse", "finalbody", "handlers"):
                visit(getattr(statement, field, None) or [], inner)
            for case in getattr(statement, "cases", None) or []:
                visit(case.body, inner)

    visit(ast.parse(path.read_text(), str(path)).body, False)
    return found


def imported_packages(path: Path) -> set[str]:
    """The top-level packages a source file imports (absolute imports only)."""
    return {found.package for found in imports_of(path)}


def is_ours(package: str) -> bool:
    return package.startswith("dronewrapper") or package == "drone_wrapper"


class Source(NamedTuple):
    """One source file: its top-level package, its dotted module name and its imports."""

    package: str
    module: str
    imports: list[Import]


@cache
def sources() -> dict[str, Source]:
    """Each source file of a distribution (repo-relative path) -> what it is and imports."""
    roots = [REPO / part for part in SDK_PARTS] + [REPO / "sim", REPO / "compose"]
    roots += [p.parent for p in sorted((REPO / "services").glob("*/pyproject.toml"))]
    found = {}
    for root in roots:
        for path in sorted(root.rglob("*.py")):
            inside = path.relative_to(root).with_suffix("").parts
            if inside[0] in (".venv", "build") or inside[0].endswith(".egg-info"):
                continue
            module = ".".join(inside[:-1] if inside[-1] == "__init__" else inside)
            relative = path.relative_to(REPO).as_posix()
            found[relative] = Source(inside[0], module, imports_of(path))
    return found


def allowed(package: str) -> set[str] | None:
    """The project packages ``package`` may import (None: any of them)."""
    if package in SDK:
        return set(SDK)
    if package in LIBRARIES:
        return SDK | {package}
    if package in SERVICE_PACKAGES:
        return SDK | LIBRARIES | {package}
    if package == "dronewrapper_sim":
        return SDK | LIBRARIES | SERVICE_PACKAGES | {package}
    return None


def is_tool(relative: str) -> bool:
    return relative.startswith(TOOLS)


def part_of(module: str) -> str | None:
    """Which distribution of ``dronewrapper`` holds ``module`` (None: not ours, or not there)."""
    parts = module.split(".")
    for n in range(len(parts), 0, -1):
        path = "/".join(parts[:n])
        for part in SDK_PARTS:
            there = (REPO / part / f"{path}.py").is_file() or (REPO / part / path).is_dir()
            if there and (n > 1 or part == "sdk"):
                return part
    return None


def names_a_tool(found: Import) -> bool:
    return part_of(found.module) == "tools"


@cache
def breaks() -> frozenset[tuple[str, str]]:
    """Every (file, imported project package) that its floor does not allow."""
    found = set()
    for relative, (package, _, imports) in sources().items():
        rule = allowed(package)
        if rule is None:
            continue
        if is_tool(relative):  # anything on board below the graphs
            rule = rule | {i.package for i in imports if i.package != COMPOSE}
        for imported in imports:
            if is_ours(imported.package) and imported.package not in rule:
                found.add((relative, imported.package))
    return frozenset(found)


def test_no_import_breaks_a_floor_rule_beyond_the_known_ones():
    assert breaks() - KNOWN == set()


def test_the_known_breaks_are_still_there():
    assert KNOWN - breaks() == set()


def test_the_contract_imports_nothing_of_ours_but_itself():
    wrong = [
        (relative, i.module)
        for relative, (_, _, imports) in sources().items()
        if relative.startswith("contract/")
        for i in imports
        if is_ours(i.package) and not (i.module == CONTRACT or i.module.startswith(CONTRACT + "."))
    ]
    assert wrong == []


def test_no_service_imports_another_service():
    wrong = [
        (relative, i.package)
        for relative, (package, _, imports) in sources().items()
        if package in PACKAGES
        for i in imports
        if i.package in SERVICE_PACKAGES and i.package != package
    ]
    assert wrong == []


def test_each_distribution_of_the_sdk_imports_only_those_below_it():
    """contract < runtime < client < tools, a lazy import included: a laptop's install of
    the client (contract, runtime, client) never needs a tool."""
    wrong = []
    for relative, (_, _, imports) in sources().items():
        part = relative.split("/")[0]
        if part not in SDK_PARTS:
            continue
        below = SDK_PARTS[: SDK_PARTS.index(part) + 1]
        for found in imports:
            if found.package == "dronewrapper" and part_of(found.module) not in (*below, None):
                wrong.append((relative, found.module))
    assert wrong == []


def test_the_thin_client_loads_no_bridge_rule_and_no_ros2_codec():
    """Outside the tools, no SDK module names an on-board package (a lazy import included);
    the client's distribution depends only on the contract and the runtime (a laptop installs
    ``./contract ./runtime ./sdk``)."""
    wrong = [
        (relative, i.module)
        for relative, (package, _, imports) in sources().items()
        if package in SDK and not is_tool(relative)
        for i in imports
        if (is_ours(i.package) and i.package not in SDK) or names_a_tool(i)
    ]
    assert wrong == []
    ours = ("dronewrapper-", "dronewrapper_")
    allowed_parts = {"contract": set(), "runtime": {"dronewrapper-contract"}}
    allowed_parts["sdk"] = {"dronewrapper-contract", "dronewrapper-runtime"}
    for part, allowed_names in allowed_parts.items():
        project = tomllib.loads((REPO / part / "pyproject.toml").read_text())["project"]
        extras = [r for extra in project.get("optional-dependencies", {}).values() for r in extra]
        named = {r.split("[")[0] for r in [*project["dependencies"], *extras] if r.startswith(ours)}
        assert named <= allowed_names, (part, named)


def test_the_simulator_does_not_import_the_graphs():
    wrong = [
        (relative, i.module)
        for relative, (package, _, imports) in sources().items()
        if package == "dronewrapper_sim"
        for i in imports
        if i.package == COMPOSE
    ]
    assert wrong == []


def test_the_rule_sees_an_import_from_a_higher_floor(tmp_path):
    source = tmp_path / "x.py"
    source.write_text(
        "import dronewrapper_compose.launcher\nfrom dronewrapper.msgs import registry\n"
        "def f():\n    import dronewrapper_ros2_codec\n"
    )
    assert imported_packages(source) == {
        "dronewrapper_compose",
        "dronewrapper",
        "dronewrapper_ros2_codec",
    }
    assert [i.lazy for i in imports_of(source)] == [False, False, True]
    assert "dronewrapper_compose" not in allowed("dronewrapper_sim")
    assert "dronewrapper_bridge_tello" not in allowed("dronewrapper_bridge_mavlink")
    assert "dronewrapper_ros2_gateway" not in allowed("dronewrapper_bridge_mavlink")
    assert "dronewrapper_ros2_codec" in allowed("dronewrapper_bridge_px4_zenoh")
    assert "dronewrapper_bridge_base" not in allowed("dronewrapper")
    assert [part_of(m) for m in ("dronewrapper.msgs.registry", "dronewrapper.runtime.node")] == [
        "contract",
        "runtime",
    ]
    assert [part_of(m) for m in ("dronewrapper.DroneWrapper", "dronewrapper.cli.main")] == [
        "sdk",
        "tools",
    ]


def module_graph(found: dict[str, Source]) -> dict[str, set[str]]:
    """Module -> the project modules it imports, at module level or inside a function (an
    import names a module: ``from a.b import c`` is ``a.b.c`` when that is one, else ``a.b``;
    never the packages above it)."""
    modules = {source.module for source in found.values()}

    def nearest(name: str) -> str | None:
        while name and name not in modules:
            name = name.rpartition(".")[0]
        return name or None

    graph: dict[str, set[str]] = {}
    for source in found.values():
        targets = {nearest(i.module) for i in source.imports} - {None, source.module}
        graph.setdefault(source.module, set()).update(t for t in targets if t is not None)
    return graph


def circles(graph: Mapping[str, set[str]]) -> set[frozenset[str]]:
    """The strongly connected components of more than one node (Tarjan, iterative)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    found: set[frozenset[str]] = set()
    for start in sorted(graph):
        if start in index:
            continue
        work = [(start, iter(sorted(graph[start])))]
        index[start] = low[start] = len(index)
        stack.append(start)
        on_stack.add(start)
        while work:
            node, children = work[-1]
            child = next(children, None)
            if child is not None:
                if child not in index:
                    index[child] = low[child] = len(index)
                    stack.append(child)
                    on_stack.add(child)
                    work.append((child, iter(sorted(graph.get(child, ())))))
                elif child in on_stack:
                    low[node] = min(low[node], index[child])
                continue
            work.pop()
            if work:
                parent = work[-1][0]
                low[parent] = min(low[parent], low[node])
            if low[node] == index[node]:
                component = set()
                while True:
                    member = stack.pop()
                    on_stack.discard(member)
                    component.add(member)
                    if member == node:
                        break
                if len(component) > 1:
                    found.add(frozenset(component))
    return found


def test_no_import_circle_beyond_the_known_ones():
    """A circle: modules that reach each other by imports (a strongly connected component of
    more than one), an import inside a function counted as one at module level: either way
    they cannot be read, tested or moved one without the other. The known ones may only go."""
    new = circles(module_graph(sources())) - KNOWN_CIRCLES
    assert new == set(), [sorted(circle) for circle in new]


def test_the_known_circles_are_still_there():
    assert KNOWN_CIRCLES - circles(module_graph(sources())) == set()


def test_a_circle_is_found_through_an_import_inside_a_function(tmp_path):
    (tmp_path / "a.py").write_text("import b\n")
    (tmp_path / "b.py").write_text("if True:\n    def f():\n        from a import g\n")
    (tmp_path / "c.py").write_text("import a\n")
    found = {p.name: Source("", p.stem, imports_of(p)) for p in sorted(tmp_path.glob("*.py"))}
    assert module_graph(found) == {"a": {"b"}, "b": {"a"}, "c": {"a"}}
    assert circles(module_graph(found)) == {frozenset({"a", "b"})}
