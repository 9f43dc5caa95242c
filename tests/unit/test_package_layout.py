"""Every distribution is a folder with its ``pyproject.toml`` and one package inside, and every
package's folder has its import name, so a reader (or a tool) goes from ``import dronewrapper_x``
to the file without a mapping table: ``services/<name>/dronewrapper_<name>/``."""

from __future__ import annotations

import importlib
import pkgutil
from pathlib import Path

import pytest
import tomllib

REPO = Path(__file__).resolve().parents[2]
SERVICES = sorted(p.parent for p in (REPO / "services").glob("*/pyproject.toml"))
SDK_PARTS = [REPO / d for d in ("contract", "runtime", "sdk", "tools")]
"""The ``dronewrapper`` package's four distributions."""
DISTRIBUTIONS = [*SDK_PARTS, *SERVICES, REPO / "sim", REPO / "compose"]


def packages_in_repo() -> list[tuple[str, Path]]:
    found = []
    for root in DISTRIBUTIONS:
        for info in pkgutil.iter_modules([str(root)]):
            if info.ispkg:
                found.append((info.name, root / info.name))
    return found


def test_the_design_names_each_service_folder():
    names = {p.name for p in SERVICES}
    assert {"bridge_mavlink", "bridge_tello", "camera_victure", "perception", "controller"} <= names


@pytest.mark.parametrize("name,folder", packages_in_repo(), ids=lambda v: str(v))
def test_the_import_name_is_the_folder_name(name: str, folder: Path):
    module = importlib.import_module(name)
    assert Path(module.__file__).resolve().parent == folder.resolve()


@pytest.mark.parametrize("service", SERVICES, ids=lambda p: p.name)
def test_a_service_is_a_distribution_holding_its_package(service: Path):
    project = tomllib.loads((service / "pyproject.toml").read_text())["project"]
    assert project["name"] == "dronewrapper-" + service.name.replace("_", "-")
    assert (service / f"dronewrapper_{service.name}" / "__init__.py").is_file()
    assert any(dep.startswith("dronewrapper") for dep in project["dependencies"])


def test_every_folder_under_services_is_a_distribution():
    for entry in (REPO / "services").iterdir():
        if entry.is_dir() and not entry.name.startswith((".", "__")):
            assert (entry / "pyproject.toml").is_file(), entry


def test_setup_installs_every_distribution():
    makefile = (REPO / "Makefile").read_text()
    assert "services/*/pyproject.toml" in makefile
    root = tomllib.loads((REPO / "pyproject.toml").read_text())["project"]
    named = {dep.split("[")[0] for dep in root["dependencies"]}
    for dist in DISTRIBUTIONS:
        name = tomllib.loads((dist / "pyproject.toml").read_text())["project"]["name"]
        assert name in named or name == "dronewrapper", name


@pytest.mark.parametrize("dist", DISTRIBUTIONS, ids=lambda p: p.name)
def test_an_editable_install_is_a_plain_path_entry(dist: Path):
    """With its packages declared beside its pyproject.toml (``package-dir = {"" = "."}``),
    setuptools installs a distribution editable as a ``.pth`` path entry; without it, through
    an import hook whose install prints a warning block (twelve blocks before the demo)."""
    config = tomllib.loads((dist / "pyproject.toml").read_text())
    assert config["tool"]["setuptools"]["package-dir"] == {"": "."}


def test_make_setup_installs_the_root_distribution_as_it_is():
    """The root holds no code (``packages = []``): an editable install of it would be the same
    import hook and warning block for nothing."""
    root = tomllib.loads((REPO / "pyproject.toml").read_text())
    assert root["tool"]["setuptools"]["packages"] == []
    makefile = (REPO / "Makefile").read_text().splitlines()
    installs = [line for line in makefile if "$(DISTS:%=-e ./%)" in line]
    assert installs, "make setup installs the distributions"
    for install in installs:  # setup (with the test tools) and onboard (without)
        assert "-e '.[dev]'" not in install and "-e ." not in install.replace("-e ./", "")
    assert any(" '.[dev]'" in install for install in installs)


def test_make_test_compiles_every_distributions_bytecode_before_the_suite():
    """The suite's processes read compiled bytecode rather than each compiling every module
    it imports (nothing writes it where PYTHONDONTWRITEBYTECODE is set)."""
    makefile = (REPO / "Makefile").read_text()
    bytecode = next(line for line in makefile.splitlines() if line.startswith("BYTECODE"))
    assert "-m compileall" in bytecode and "$(DISTS)" in bytecode, bytecode
    recipe = makefile.split("\ntest: ", 1)[1].split("\n\n", 1)[0].splitlines()[1:]
    compiled = next(i for i, line in enumerate(recipe) if "$(BYTECODE)" in line)
    suite = next(i for i, line in enumerate(recipe) if "-m pytest" in line)
    assert compiled < suite, recipe
