"""The ``dronewrapper`` command finds the on-board stack's subcommands through the
``dronewrapper.commands`` entry points its distributions declare, and names none of them."""

from __future__ import annotations

import importlib
import importlib.metadata

import tomllib

from dronewrapper import cli
from support import REPO


def declared() -> dict[str, str]:
    """Subcommand -> ``module:function`` over every distribution's pyproject.toml."""
    found: dict[str, str] = {}
    for pyproject in sorted(REPO.glob("*/pyproject.toml")) + sorted(
        REPO.glob("services/*/pyproject.toml")
    ):
        project = tomllib.loads(pyproject.read_text())["project"]
        for name, target in project.get("entry-points", {}).get(cli.COMMANDS_GROUP, {}).items():
            assert name not in found, f"{name} declared twice"
            found[name] = target
    return found


def test_every_stack_command_is_declared_by_a_distribution_and_resolves():
    commands = declared()
    assert set(commands) == set(cli.STACK_COMMANDS)
    for name, target in commands.items():
        module, _, function = target.partition(":")
        assert callable(getattr(importlib.import_module(module), function)), name


def test_the_sdk_declares_no_stack_command():
    for part in ("contract", "runtime", "sdk", "tools"):
        project = tomllib.loads((REPO / part / "pyproject.toml").read_text())["project"]
        assert cli.COMMANDS_GROUP not in project.get("entry-points", {}), part


def test_the_installed_entry_points_are_the_declared_ones():
    installed = importlib.metadata.entry_points(group=cli.COMMANDS_GROUP)
    assert {ep.name: ep.value for ep in installed} == declared()


class _Missing:
    name = "up"

    def load(self):
        raise ModuleNotFoundError("no module named 'yaml'", name="yaml")


def _run_up(found: list, monkeypatch, capsys) -> str:
    monkeypatch.setattr(importlib.metadata, "entry_points", lambda group: found)
    assert cli.main(["up", "sim_iris"]) == 2
    err = capsys.readouterr().err
    assert "dronewrapper up: needs the on-board stack" in err and "make setup" in err
    return err


def test_a_stack_command_without_the_stack_says_what_it_needs(monkeypatch, capsys):
    assert "is missing" not in _run_up([], monkeypatch, capsys)


def test_a_stack_command_missing_a_module_names_it(monkeypatch, capsys):
    assert "(yaml is missing)" in _run_up([_Missing()], monkeypatch, capsys)
