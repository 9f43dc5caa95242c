"""Every relative link in the repository's Markdown resolves to a file inside the repository."""

import os
import re
from functools import cache

import pytest

from support import REPO

LINK = re.compile(r"\[[^\]]*\]\(([^)\s]+)\)")


SKIPPED = {"node_modules", "build", "dist", "out", "__pycache__"}  # built or installed, not ours


@cache
def markdown_files() -> list[str]:
    """The repository's own Markdown: every ``*.md`` outside hidden and built folders (which
    are not walked into)."""
    found = []
    for folder, subfolders, files in os.walk(REPO):
        subfolders[:] = [
            f
            for f in subfolders
            if not (f.startswith(".") or f in SKIPPED or f.endswith(".egg-info"))
        ]
        found += [os.path.join(folder, name) for name in files if name.endswith(".md")]
    return sorted(os.path.relpath(path, REPO) for path in found)


def relative_links(text: str) -> list[str]:
    return [
        target.split("#", 1)[0]
        for target in LINK.findall(text)
        if not re.match(r"[a-z]+:", target) and not target.startswith("#")
    ]


@pytest.mark.parametrize("doc", markdown_files())
def test_links_resolve_inside_the_repository(doc: str):
    source = REPO / doc
    for target in relative_links(source.read_text(encoding="utf-8")):
        resolved = (source.parent / target).resolve()
        assert resolved.is_relative_to(REPO), f"{doc}: {target} points outside the repository"
        assert resolved.exists(), f"{doc}: {target} does not exist"


def test_the_link_finder_sees_links():
    assert relative_links("see [a](docs/a.md#x), [b](https://x.org) and [c](#top)") == ["docs/a.md"]
