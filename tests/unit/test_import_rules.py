"""Which floor of the house may import which, read from the source (``ast``, no import run).

Floors from the bottom: the SDK (``dronewrapper``, what everything stands on), the bridges'
shared base (``dronewrapper_bridge_base``), the services, the simulator, the graphs
(``dronewrapper_compose``, which names them all). A package imports only floors below it, and
a service imports no other service. :data:`KNOWN` lists the imports that break a rule today,
each with its file: the list may only shrink (a new break fails, and so does a listed one that
is gone, so the list stays true).
"""

from __future__ import annotations

import ast
from functools import cache
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]
SERVICES = sorted(p.parent.name for p in (REPO / "services").glob("*/pyproject.toml"))
SERVICE_PACKAGES = {f"dronewrapper_{name}" for name in SERVICES}
SHARED_BASE = "dronewrapper_bridge_base"

KNOWN = {
    ("sdk/dronewrapper/cli.py", "dronewrapper_compose"),
    ("services/bridge_mavlink/dronewrapper_bridge_mavlink/config.py", "dronewrapper_ros2_gateway"),
    ("services/bridge_mavlink/dronewrapper_bridge_mavlink/node.py", "dronewrapper_ros2_gateway"),
    ("services/bridge_tello/dronewrapper_bridge_tello/config.py", "dronewrapper_ros2_gateway"),
    ("services/bridge_tello/dronewrapper_bridge_tello/node.py", "dronewrapper_ros2_gateway"),
}
"""(file, imported package) pairs that break a rule today."""


def imported_packages(path: Path) -> set[str]:
    """The top-level packages a source file imports (absolute imports only)."""
    found = set()
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.Import):
            found.update(alias.name.split(".")[0] for alias in node.names)
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            found.add(node.module.split(".")[0])
    return found


def allowed(package: str) -> set[str] | None:
    """The project packages ``package`` may import (None: any of them)."""
    below_services = {"dronewrapper", "drone_wrapper", SHARED_BASE}
    if package in ("dronewrapper", "drone_wrapper"):
        return {"dronewrapper", "drone_wrapper"}
    if package == SHARED_BASE:
        return {"dronewrapper", SHARED_BASE}
    if package in SERVICE_PACKAGES:
        return below_services | {package}
    if package == "dronewrapper_sim":
        return below_services | SERVICE_PACKAGES | {package}
    return None


@cache
def breaks() -> frozenset[tuple[str, str]]:
    """Every (file, imported project package) that its floor does not allow."""
    roots = [REPO / "sdk", REPO / "sim", *(REPO / "services" / name for name in SERVICES)]
    found = set()
    for root in roots:
        for path in root.rglob("*.py"):
            relative = path.relative_to(REPO)
            if ".venv" in relative.parts or "build" in relative.parts:
                continue
            package = (
                relative.parts[1] if relative.parts[0] in ("sdk", "sim") else relative.parts[2]
            )
            rule = allowed(package)
            if rule is None:
                continue
            for imported in imported_packages(path):
                is_ours = imported.startswith("dronewrapper") or imported == "drone_wrapper"
                if is_ours and imported not in rule:
                    found.add((relative.as_posix(), imported))
    return frozenset(found)


def test_no_import_breaks_a_floor_rule_beyond_the_known_ones():
    assert breaks() - KNOWN == set()


def test_the_known_breaks_are_still_there():
    assert KNOWN - breaks() == set()


def test_the_rule_sees_an_import_from_a_higher_floor(tmp_path):
    source = tmp_path / "x.py"
    source.write_text(
        "import dronewrapper_compose.launcher\nfrom dronewrapper.msgs import registry\n"
    )
    assert imported_packages(source) == {"dronewrapper_compose", "dronewrapper"}
    assert "dronewrapper_compose" not in allowed("dronewrapper_sim")
    assert "dronewrapper_bridge_tello" not in allowed("dronewrapper_bridge_mavlink")
