"""Every package's folder has its import name, so a reader (or a tool) can go from
``import dronewrapper_x`` to the file without a mapping table."""

from __future__ import annotations

import importlib
import pkgutil
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]
ROOTS = ("sdk", "services", "sim", "compose")


def packages_in_repo() -> list[tuple[str, Path]]:
    found = []
    for root in ROOTS:
        for info in pkgutil.iter_modules([str(REPO / root)]):
            if info.ispkg:
                found.append((info.name, REPO / root / info.name))
    return found


def test_every_root_holds_packages():
    names = {name for name, _ in packages_in_repo()}
    assert {
        "dronewrapper",
        "dronewrapper_sim",
        "dronewrapper_compose",
        "dronewrapper_bridge_mavlink",
        "dronewrapper_bridge_tello",
    } <= names


@pytest.mark.parametrize("name,folder", packages_in_repo(), ids=lambda v: str(v))
def test_the_import_name_is_the_folder_name(name: str, folder: Path):
    module = importlib.import_module(name)
    assert Path(module.__file__).resolve().parent == folder.resolve()


def test_services_are_all_packages_named_for_import():
    for entry in (REPO / "services").iterdir():
        if entry.is_dir() and not entry.name.startswith((".", "__")):
            assert entry.name.startswith("dronewrapper_"), entry
            assert (entry / "__init__.py").is_file(), entry
