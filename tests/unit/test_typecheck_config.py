"""`make typecheck` covers every package of the repository: the list in pyproject.toml's
[tool.mypy] names each distribution's package (a new service is not left unchecked)."""

from __future__ import annotations

from pathlib import Path

import tomllib

REPO = Path(__file__).resolve().parents[2]


def _packages() -> set[str]:
    """Each distribution's top-level package folder, relative to the repository (a part of
    ``dronewrapper`` from the contract, the runtime or the tools has no ``__init__.py``)."""
    found = set()
    for project in REPO.glob("**/pyproject.toml"):
        if project.parent == REPO or ".venv" in project.parts:
            continue
        for init in project.parent.glob("*/__init__.py"):
            found.add(init.parent.relative_to(REPO).as_posix())
        if (project.parent / "dronewrapper").is_dir():
            found.add((project.parent / "dronewrapper").relative_to(REPO).as_posix())
    return found


def test_every_package_is_type_checked():
    config = tomllib.loads((REPO / "pyproject.toml").read_text())["tool"]["mypy"]
    assert set(config["files"]) == _packages()


def test_no_package_of_ours_is_exempt():
    """Only third-party modules may be unchecked (ignore_missing_imports), none of ours."""
    config = tomllib.loads((REPO / "pyproject.toml").read_text())["tool"]["mypy"]
    for override in config.get("overrides", []):
        modules = override["module"]
        modules = [modules] if isinstance(modules, str) else modules
        assert not any(m.startswith(("dronewrapper", "drone_wrapper")) for m in modules)
        assert "ignore_errors" not in override
