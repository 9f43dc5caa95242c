"""A bridge's command line: flags that stand for one ``--set key=value`` each, and the bridge's
entry point, :func:`bridge_main` (``run_service`` with those flags added)."""

from __future__ import annotations

import argparse
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from dronewrapper.runtime.ports import Ports
from dronewrapper.runtime.service import run_service


@dataclass(frozen=True)
class Shortcut:
    """``flag VALUE`` is ``--set key=VALUE`` (``flag`` like ``--baud``; ``kind`` parses VALUE)."""

    flag: str
    key: str
    metavar: str
    help: str
    kind: Callable[[str], Any] = str

    @property
    def dest(self) -> str:
        """The flag's attribute on the parsed arguments (``--baud`` -> ``baud``)."""
        return self.flag.removeprefix("--").replace("-", "_")


class Shortcuts:
    """A bridge's shortcut flags, added to its parser and turned into config overrides."""

    def __init__(self, *shortcuts: Shortcut) -> None:
        self.shortcuts = shortcuts

    def add_flags(self, parser: argparse.ArgumentParser) -> None:
        for s in self.shortcuts:
            parser.add_argument(
                s.flag,
                metavar=s.metavar,
                type=s.kind,
                help=f"{s.help} (same as --set {s.key}={s.metavar})",
            )

    def as_overrides(self, args: argparse.Namespace, overrides: list[str]) -> None:
        """Append the flags given to ``overrides`` (``key=value``, as ``--set``)."""
        for s in self.shortcuts:
            value = getattr(args, s.dest)
            if value:
                overrides.append(f"{s.key}={value}")


def bridge_main(
    name: str,
    description: str | None,
    config_type: type[Any],
    run: Callable[[Any, Any], int | None],
    ports: Ports,
    shortcuts: Shortcuts,
    argv: list[str] | None,
) -> int:
    """Run the bridge ``name`` as a process (``python -m``): its flags and shortcuts parsed, its
    config loaded, ``run(node, config)`` on a node holding ``ports``."""
    return run_service(
        name,
        description,
        config_type,
        run,
        argv,
        add_args=shortcuts.add_flags,
        configure=shortcuts.as_overrides,
        ports=ports,
    )
