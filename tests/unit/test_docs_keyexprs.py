"""Every key expression in a documented ``echo``/``record``/``foxglove``/``replay`` command is
quoted: unquoted, the shell expands ``sim/**`` into files and the world is never recorded."""

from __future__ import annotations

import re
import shlex

import pytest
from test_docs_links import markdown_files

from support import REPO

COMMAND = re.compile(r"dronewrapper (echo|record|foxglove|replay)\b([^`\n#|]*)")
ENDPOINT = re.compile(r"[a-z]+/[^/]*:\d+")  # tcp/HOST:PORT, not a key expression
VALUE_FLAGS = set(
    [
        "-o",
        "--output",
        "--info",
        "--connect",
        "--identity",
        "--duration",
        "--rate",
        "--count",
        "-n",
        "--port",
        "--host",
        "--jpeg-quality",
        "--image-rate",
        "--start",
        "--compression",
        "--seconds",
        "--ns",
        "--namespace",
        "--mode",
        "--listen",
    ]
)


def unquoted_keyexprs(line: str) -> list[str]:
    """The key expressions written unquoted in the documented commands on ``line``."""
    found = []
    for match in COMMAND.finditer(line):
        words = match.group(2).split()
        after_value_flag = False
        for word in words:
            if after_value_flag or word.startswith(("-", "[", "<", "KEYEXPR", "FILE")):
                after_value_flag = word in VALUE_FLAGS
                continue
            if ENDPOINT.match(word) or word == "/":
                continue
            if "/" in word and not word.endswith((".mcap", ".md")) and "'" not in word:
                found.append(word)
    return found


def test_the_finder_sees_an_unquoted_key_expression():
    assert unquoted_keyexprs("dronewrapper record drone/** sim/** -o f.mcap") == [
        "drone/**",
        "sim/**",
    ]
    assert unquoted_keyexprs("dronewrapper record 'drone/**' -o out/f.mcap") == []
    assert unquoted_keyexprs("dronewrapper echo 'x/y' --connect tls/1.2.3.4:7448") == []
    assert shlex.split("dronewrapper record 'sim/**'")[-1] == "sim/**"


@pytest.mark.parametrize("doc", markdown_files())
def test_documented_key_expressions_are_quoted(doc: str):
    text = (REPO / doc).read_text(encoding="utf-8")
    bad = [(n, k) for n, line in enumerate(text.splitlines(), 1) for k in unquoted_keyexprs(line)]
    assert not bad, f"{doc}: quote these key expressions (line, key): {bad}"
