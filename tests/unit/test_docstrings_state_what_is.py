"""Docstrings, comments and the docs say what is: no project history ("issue 20", "used to
be", "as the SDK's calls always did") and no apology for a file's size ("Size: over 400
lines")."""

from __future__ import annotations

import re

import pytest

from support import REPO

HISTORY = re.compile(
    r"\bissue \d+|\bSize: (just )?over \d+ lines|\balways did\b|\bused to (be|go|print|say)\b"
    r"|\bas before\b|\b(do|does) not exist yet\b|\bnot available yet\b",
    re.IGNORECASE,
)
OUTSIDE = re.compile(r"\bDESIGN\.md\b")  # a document outside the repository (ours: docs/design.md)
CODE = ["contract", "runtime", "sdk", "tools", "services", "sim", "compose", "bench", "examples"]
# dronewrapper/drone.py is being split into smaller modules by a change of its own, which
# removes its size note with it
SPLIT_ELSEWHERE = {"sdk/dronewrapper/drone.py"}


def sources() -> list[str]:
    found = []
    for top in CODE:
        for path in (REPO / top).rglob("*.py"):
            relative = str(path.relative_to(REPO))
            if ".egg-info" not in relative and relative not in SPLIT_ELSEWHERE:
                found.append(relative)
    pages = [REPO / "README.md", *(REPO / "docs").glob("*.md"), *REPO.glob("*/*/README.md")]
    docs = [str(p.relative_to(REPO)) for p in pages if ".venv" not in p.parts]
    return sorted(found) + sorted(docs)


@pytest.mark.parametrize("source", sources())
def test_no_history_and_no_size_apology(source: str):
    text = (REPO / source).read_text(encoding="utf-8")
    hits = [
        f"{n}: {line.strip()}"
        for n, line in enumerate(text.splitlines(), 1)
        if HISTORY.search(line) or OUTSIDE.search(line)
    ]
    assert not hits, f"{source} narrates history or apologises; state what is: {hits}"


def test_the_pattern_sees_history():
    assert HISTORY.search("Size: over 400 lines: one concern")
    assert HISTORY.search("(previous, issue 20: 10 ms)")
    assert not HISTORY.search("the heading, used to rotate body velocities")
