"""The modules beside a bridge's core see it through the port each states, never whole: in
every bridge package only the node imports its ``core`` module (at module level, under
TYPE_CHECKING or in a function), and no function there takes a core typed as ``Any``."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

SERVICES = Path(__file__).resolve().parents[2] / "services"
BRIDGES = ("bridge_mavlink", "bridge_px4_zenoh", "bridge_tello")


def modules(bridge: str) -> dict[str, ast.Module]:
    package = next((SERVICES / bridge).glob("dronewrapper_*/__init__.py")).parent
    return {path.stem: ast.parse(path.read_text()) for path in sorted(package.glob("*.py"))}


def imported(tree: ast.Module) -> set[str]:
    """The modules ``tree`` imports, anywhere in it (``from p import m`` names ``p.m`` too)."""
    found: set[str] = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            found |= {alias.name for alias in node.names}
        elif isinstance(node, ast.ImportFrom) and node.module:
            found |= {node.module} | {f"{node.module}.{alias.name}" for alias in node.names}
    return found


@pytest.mark.parametrize("bridge", BRIDGES)
def test_only_the_node_imports_the_core(bridge):
    found = modules(bridge)
    core = f"dronewrapper_{bridge}.core"
    importers = {name for name, tree in found.items() if core in imported(tree)}
    assert importers == {"node"}


@pytest.mark.parametrize("bridge", BRIDGES)
def test_no_core_parameter_is_untyped(bridge):
    untyped = []
    for name, tree in modules(bridge).items():
        aliases = {
            target.id
            for node in tree.body
            if isinstance(node, ast.Assign) and ast.unparse(node.value) == "Any"
            for target in node.targets
            if isinstance(target, ast.Name)
        }
        for node in ast.walk(tree):
            if isinstance(node, ast.FunctionDef):
                for arg in node.args.args:
                    kind = ast.unparse(arg.annotation) if arg.annotation else "Any"
                    if arg.arg == "core" and (kind == "Any" or kind in aliases):
                        untyped.append(f"{name}.{node.name}")
    assert untyped == []
