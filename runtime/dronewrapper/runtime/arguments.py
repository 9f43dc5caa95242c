"""Command-line parsers as every command of the project builds them.

:class:`CommandParser` is :class:`argparse.ArgumentParser` with two rules: an option is taken
only under its whole name (``--scenari`` is an error, not ``--scenario``: a shortened option
would silently change meaning the day a second option shares its start), and ``--help`` is
plain text (the reST markup of the docstrings it is made from, double backticks and roles
such as ``:func:``, is dropped and the names kept). Sub-commands
(``add_subparsers().add_parser``) are CommandParsers too.
"""

from __future__ import annotations

import argparse
import re
from typing import Any

_ROLE = re.compile(r":[a-z]+(?::[a-z]+)?:`~?([^`]+)`")  # :func:`name`, :class:`~a.b.C`


def plain_text(text: str) -> str:
    """``text`` from a docstring as a terminal shows it: reST's double backticks and roles
    (``:class:`Name```) dropped, their contents kept."""
    return _ROLE.sub(r"\1", text).replace("``", "")


class CommandParser(argparse.ArgumentParser):
    """An ArgumentParser that takes whole option names only and prints plain-text help."""

    def __init__(self, *, allow_abbrev: bool = False, **kwargs: Any) -> None:
        super().__init__(allow_abbrev=allow_abbrev, **kwargs)

    def format_usage(self) -> str:
        return plain_text(super().format_usage())

    def format_help(self) -> str:
        return plain_text(super().format_help())


def first_line(doc: str | None) -> str | None:
    """The first line of a module's docstring as a parser's description (plain text)."""
    return plain_text(doc.strip().splitlines()[0]) if doc and doc.strip() else None
