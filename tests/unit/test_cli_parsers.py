"""Every command-line parser of the project takes whole option names only and prints plain help.

Each command is run up to its parse (``parse_known_args`` is replaced by one that hands the
parser over and stops), so the test sees the very parser a user gets: it must refuse an
abbreviated option (``--scenari`` for ``--scenario``), and its help, sub-commands' included,
must carry no reST markup. A source scan makes sure no parser is built any other way.
"""

from __future__ import annotations

import argparse
import ast
import importlib
import inspect
import runpy
import sys
from collections.abc import Callable
from unittest import mock

import pytest

from support import REPO

CODE_DIRS = (
    "contract",
    "runtime",
    "sdk",
    "tools",
    "services",
    "sim",
    "compose",
    "bench",
    "examples",
    "tests/replay",
)

DRONEWRAPPER = [
    "router", "echo", "alive", "doctor", "keys", "mavlink-forward", "up", "sim", "detect",
    "station", "ros2", "record", "replay", "foxglove", "install", "uninstall",
]  # fmt: skip
SERVICES = [
    "dronewrapper_bridge_mavlink", "dronewrapper_bridge_tello", "dronewrapper_camera_victure",
    "dronewrapper_controller", "dronewrapper_perception", "dronewrapper_ground_station",
    "dronewrapper_ros2_gateway", "dronewrapper_sim", "dronewrapper_compose",
]  # fmt: skip
MODULE_MAINS = [
    "dronewrapper_compose.demo", "dronewrapper_bridge_mavlink.provision",
    "dronewrapper_sim.serial_relay",
    *(f"bench.{p.stem}" for p in sorted((REPO / "bench").glob("*.py"))
      if "ArgumentParser(" in p.read_text() or "CommandParser(" in p.read_text()),
]  # fmt: skip
EXAMPLES = sorted(p.name for p in (REPO / "examples").glob("*.py") if "argparse" in p.read_text())


class Captured(Exception):
    def __init__(self, parser: argparse.ArgumentParser) -> None:
        self.parser = parser


def _capture(start: Callable[[], object]) -> argparse.ArgumentParser:
    """The parser ``start()`` builds, taken at its first parse."""

    def hand_over(self, args=None, namespace=None):
        raise Captured(self)

    with mock.patch.object(argparse.ArgumentParser, "parse_known_args", hand_over):
        try:
            start()
        except Captured as done:
            return done.parser
    raise AssertionError("no parser was built")


def _run_module(name: str) -> None:
    sys.modules.pop(f"{name}.__main__", None)
    with mock.patch.object(sys, "argv", [name]):
        runpy.run_module(name, run_name="__main__")


def _run_example(name: str) -> None:
    with mock.patch.object(sys, "argv", [name]):
        runpy.run_path(str(REPO / "examples" / name), run_name="__main__")


def _run_main(name: str) -> None:
    main = importlib.import_module(name).main
    with mock.patch.object(sys, "argv", [name]):
        main(*([[]] if inspect.signature(main).parameters else []))


def _dronewrapper(command: str) -> None:
    from dronewrapper.cli import main

    main([command])


STARTS = {
    **{f"dronewrapper {c}": (lambda c=c: _dronewrapper(c)) for c in DRONEWRAPPER},
    **{f"python -m {m}": (lambda m=m: _run_module(m)) for m in SERVICES},
    **{m: (lambda m=m: _run_main(m)) for m in MODULE_MAINS},
    **{f"examples/{e}": (lambda e=e: _run_example(e)) for e in EXAMPLES},
}


def _parsers(parser: argparse.ArgumentParser) -> list[argparse.ArgumentParser]:
    """``parser`` and its sub-commands' parsers."""
    found = [parser]
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for sub in dict.fromkeys(action.choices.values()):
                found += _parsers(sub)
    return found


@pytest.mark.parametrize("command", sorted(STARTS))
def test_whole_option_names_only_and_plain_help(command):
    for parser in _parsers(_capture(STARTS[command])):
        assert parser.allow_abbrev is False, f"{parser.prog} takes abbreviated options"
        text = parser.format_help()
        assert "``" not in text and ":class:`" not in text and ":func:`" not in text, text


@pytest.mark.parametrize(
    "start",
    [
        lambda: importlib.import_module("dronewrapper_compose.demo").main(["--scenari", "x"]),
        lambda: _dronewrapper_argv(["up", "sim_iris", "--scenari", "x", "--check"]),
        lambda: _dronewrapper_argv(["ros2", "--log-lev", "DEBUG"]),
    ],
    ids=["make demo", "dronewrapper up", "dronewrapper ros2"],
)
def test_an_abbreviated_option_is_refused_by_name(start, capsys):
    with pytest.raises(SystemExit) as refused:
        start()
    assert refused.value.code == 2
    assert "unrecognized arguments: --" in capsys.readouterr().err


def _dronewrapper_argv(argv: list[str]) -> None:
    from dronewrapper.cli import main

    main(argv)


def _called(call: ast.Call) -> str:
    return call.func.attr if isinstance(call.func, ast.Attribute) else getattr(call.func, "id", "")


def test_every_parser_is_a_command_parser_or_refuses_abbreviations():
    """``argparse.ArgumentParser(...)`` only with ``allow_abbrev=False``; sub-commands of a
    CommandParser are CommandParsers."""
    offenders = []
    for folder in CODE_DIRS:
        for path in sorted((REPO / folder).rglob("*.py")):
            text = path.read_text()
            if "ArgumentParser(" not in text or path.match("runtime/arguments.py"):
                continue  # no parser built here, or CommandParser itself
            for node in ast.walk(ast.parse(text)):
                if not isinstance(node, ast.Call) or _called(node) != "ArgumentParser":
                    continue
                keywords = {k.arg: k.value for k in node.keywords}
                value = keywords.get("allow_abbrev")
                if not (isinstance(value, ast.Constant) and value.value is False):
                    offenders.append(f"{path.relative_to(REPO)}:{node.lineno}")
    assert offenders == [], f"use dronewrapper.runtime.arguments.CommandParser: {offenders}"


def test_every_command_of_the_project_is_checked():
    """A new command module appears in the parametrised test above."""
    built = set()
    for folder in ("contract", "runtime", "sdk", "tools", "services", "sim", "compose", "bench"):
        for path in (REPO / folder).rglob("*.py"):
            text = path.read_text()
            if "CommandParser(" in text and "class CommandParser" not in text:
                built.add(path.relative_to(REPO).as_posix())
    covered = {
        "tools/dronewrapper/cli.py",
        "tools/dronewrapper/record/cli.py",
        "tools/dronewrapper/keys_cli.py",
        "runtime/dronewrapper/runtime/service.py",
        "compose/dronewrapper_compose/up.py",
        "compose/dronewrapper_compose/demo.py",
        "services/perception/dronewrapper_perception/detect_cli.py",
        "services/bridge_mavlink/dronewrapper_bridge_mavlink/provision.py",
        "compose/dronewrapper_compose/install_cli.py",  # dronewrapper install / uninstall
        "sim/dronewrapper_sim/serial_relay.py",
        *(f"bench/{m.removeprefix('bench.')}.py" for m in MODULE_MAINS if m.startswith("bench.")),
    }
    assert built <= covered, f"add to STARTS: {sorted(built - covered)}"


def test_plain_text_drops_rest_markup_and_keeps_the_names():
    from dronewrapper.runtime.arguments import plain_text

    assert plain_text("``make demo``: see :func:`~a.b.run` and :class:`Node`") == (
        "make demo: see a.b.run and Node"
    )
