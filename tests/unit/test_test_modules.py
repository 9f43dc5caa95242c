"""Every test module under tests/ has a file name of its own: pytest imports a test file by its
name (tests/ holds no packages), so a second file of one name stops the whole suite at
collection."""

from __future__ import annotations

from collections import Counter
from pathlib import Path

TESTS = Path(__file__).resolve().parents[1]


def test_no_two_test_modules_share_a_name():
    names = Counter(path.name for path in TESTS.rglob("test_*.py"))
    assert [name for name, count in names.items() if count > 1] == []
