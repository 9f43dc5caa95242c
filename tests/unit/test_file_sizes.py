"""No Python file of the repository over 500 lines, and none over 400 without a reason.

Every ``.py`` file counts, tests and benchmarks included (a virtual environment, build output
and caches are not the project's). A file of 401 to 500 lines states why it stays whole in its
module docstring, in a paragraph that starts with ``Size:`` and says what would be lost by a
split (``Size: one table of every key, kept whole so that one file spells them all.``);
"over 400 lines" is no reason (``test_docstrings_state_what_is`` refuses that wording).

:data:`PENDING` lists the files over 400 lines, without a reason, that a change under way
elsewhere splits: it may only shrink (a new one fails, and so does a listed one that is now
short or gives its reason, so the list stays true).
"""

from __future__ import annotations

import ast
import os
from functools import cache
from pathlib import Path

from support import REPO

LIMIT = 500
"""No file over this many lines."""
REASON_ABOVE = 400
"""A file over this many lines gives its reason (``Size:`` in its module docstring)."""
SKIPPED_DIRS = {"build", "node_modules", "__pycache__", "results"}
"""Folders that hold no source of ours (``bench/results``: measured figures); folders whose
name starts with a dot (``.venv``, ``.git``, caches) and ``*.egg-info`` are skipped too."""

PENDING: set[str] = set()


def python_files(root: Path = REPO) -> list[Path]:
    """Every ``.py`` file under ``root`` but those of :data:`SKIPPED_DIRS` and hidden folders
    (not walked into)."""
    found = []
    for folder, subfolders, files in os.walk(root):
        subfolders[:] = [
            f
            for f in subfolders
            if not (f.startswith(".") or f in SKIPPED_DIRS or f.endswith(".egg-info"))
        ]
        found += [Path(folder, name) for name in files if name.endswith(".py")]
    return sorted(found)


def line_count(path: Path) -> int:
    return len(path.read_text(encoding="utf-8").splitlines())


def size_reason(source: str) -> str | None:
    """The reason a module docstring gives for the file's size (its ``Size:`` line), or None."""
    try:
        doc = ast.get_docstring(ast.parse(source)) or ""
    except SyntaxError:
        return None
    for line in doc.splitlines():
        if line.startswith("Size:") and line.removeprefix("Size:").strip():
            return line.removeprefix("Size:").strip()
    return None


def oversized(root: Path = REPO) -> dict[str, int]:
    """Files over :data:`LIMIT` lines, and files over :data:`REASON_ABOVE` with no reason:
    repo-relative path -> lines."""
    found = {}
    for path in python_files(root):
        lines = line_count(path)
        if lines > LIMIT or (lines > REASON_ABOVE and size_reason(path.read_text()) is None):
            found[path.relative_to(root).as_posix()] = lines
    return found


@cache
def repository_oversized() -> dict[str, int]:
    """:func:`oversized` of the repository, read once for the tests that need it."""
    return oversized()


def test_no_file_over_500_lines_and_none_over_400_without_a_reason():
    wrong = {path: lines for path, lines in repository_oversized().items() if path not in PENDING}
    assert wrong == {}, (
        f"split these files along a seam, or (401-{LIMIT} lines) say why each stays whole "
        f"on a 'Size:' line of its module docstring: {wrong}"
    )


def test_the_pending_files_are_still_over_400_lines_without_a_reason():
    found = repository_oversized()
    assert {path for path in PENDING if path not in found} == set()
    assert all(found[path] <= LIMIT for path in PENDING), {p: found[p] for p in PENDING}


def test_the_rule_sees_a_long_file_and_reads_its_reason(tmp_path):
    body = "x = 1\n" * 410
    (tmp_path / "plain.py").write_text('"""A module."""\n' + body)
    (tmp_path / "reasoned.py").write_text('"""A module.\n\nSize: one table.\n"""\n' + body)
    (tmp_path / "empty_reason.py").write_text('"""A module.\n\nSize:\n"""\n' + body)
    (tmp_path / "huge.py").write_text('"""A module.\n\nSize: one table.\n"""\n' + body * 2)
    (tmp_path / "short.py").write_text('"""A module."""\n' + "x = 1\n" * 399)
    (tmp_path / ".venv").mkdir()
    (tmp_path / ".venv" / "vendored.py").write_text(body * 2)
    assert oversized(tmp_path) == {"plain.py": 411, "empty_reason.py": 414, "huge.py": 824}
