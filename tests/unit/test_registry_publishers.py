"""The registry's ``publishers`` are true: each process it names really declares a publisher of
the topic in its source, and no process publishes a topic the registry does not say it does.

The sources are read as text (no process is started): a publisher declaration is a call to
``publisher(...)``, ``Publisher(...)`` or ``declare_publisher(...)`` (or a class wrapping one)
whose arguments name the topic, directly or through a local ``topic = registry.NAME``.
"""

from __future__ import annotations

import io
import itertools
import re
import tokenize
from collections import defaultdict
from pathlib import Path

import pytest

from dronewrapper.msgs.registry import TOPICS

REPO = Path(__file__).resolve().parents[2]
SDK = [REPO / d / "dronewrapper" for d in ("contract", "runtime", "sdk", "tools")]
"""The four distributions of the ``dronewrapper`` package."""
TOOLS = REPO / "tools" / "dronewrapper"

SOURCES: dict[str, list[Path]] = {
    "bridge": [
        REPO / "services/bridge_mavlink/dronewrapper_bridge_mavlink",
        REPO / "services/bridge_tello/dronewrapper_bridge_tello",
    ],
    "bridge_tello": [REPO / "services/bridge_tello/dronewrapper_bridge_tello"],
    "sdk": [
        p
        for root in SDK
        for p in root.rglob("*.py")
        if p.name != "mavlink_forward.py" and "record" not in p.parts
    ],
    "gcs": [TOOLS / "mavlink_forward.py"],
    "replay": [TOOLS / "record"],
    "controller": [REPO / "services/controller/dronewrapper_controller"],
    "perception": [REPO / "services/perception/dronewrapper_perception"],
    "camera_victure": [REPO / "services/camera_victure/dronewrapper_camera_victure"],
    "sim": [REPO / "sim" / "dronewrapper_sim"],
    "teleop": [REPO / "services/ground_station/dronewrapper_ground_station"],
    "tests": [REPO / "tests"],
}
"""Where each process the registry names lives."""
COMMANDS_THROUGH_THE_SDK = {"controller"}
"""Processes that publish setpoints through the SDK (its ``DroneClient`` or ``DroneWrapper``)."""
SDK_COMMANDERS = ("DroneClient(", "DroneWrapper(")

_CALL = re.compile(r"(?:declare_publisher|[Pp]ublisher)\(")
_ALIAS = re.compile(r"\b([a-z_]\w*) = (?:registry\.)?([A-Z][A-Z0-9_]+)\b")
_TUPLE = re.compile(r"^([A-Z][A-Z0-9_]*) = \(([^)]*)\)", re.MULTILINE)
_LOOP = re.compile(r"\s*for ([a-z_]\w*) in ([A-Z][A-Z0-9_]*)\b")


def _files(paths: list[Path]) -> list[Path]:
    out: list[Path] = []
    for path in paths:
        out += sorted(path.rglob("*.py")) if path.is_dir() else [path]
    return out


def _code(file: Path) -> str:
    """The file's source with its strings and comments blanked (docstring examples are not
    declarations); positions and lines are kept."""
    src = file.read_text()
    lines = src.splitlines(keepends=True)
    starts = [0, *itertools.accumulate(len(line) for line in lines)]
    chars = list(src)
    for tok in tokenize.generate_tokens(io.StringIO(src).readline):
        if tok.type in (tokenize.STRING, tokenize.COMMENT):
            begin = starts[tok.start[0] - 1] + tok.start[1]
            end = starts[tok.end[0] - 1] + tok.end[1]
            for i in range(begin, end):
                if chars[i] != "\n":
                    chars[i] = " "
    return "".join(chars)


def _arguments(src: str, start: int) -> str:
    """The text of a call's arguments, from just after its '(' to the matching ')'."""
    depth, i = 1, start
    while depth and i < len(src):
        depth += {"(": 1, ")": -1}.get(src[i], 0)
        i += 1
    return src[start:i]


def published_topics(paths: list[Path]) -> dict[str, set[str]]:
    """Registry topic names -> the files (relative) that declare a publisher of them."""
    found: dict[str, set[str]] = defaultdict(set)
    for file in _files(paths):
        if "ublisher(" not in file.read_text():
            continue  # no declaration to look at: skip the tokenizer
        src = _code(file)
        tuples = {
            name: set(re.findall(r"\b[A-Z][A-Z0-9_]+\b", items))
            for name, items in _TUPLE.findall(src)
        }
        for call in _CALL.finditer(src):
            args = _arguments(src, call.end())
            names = set(re.findall(r"\b[A-Z][A-Z0-9_]+\b", args))
            # ``{t: node.publisher(t) for t in PUBLISHED}``: the module's tuple of topics
            loop = _LOOP.match(src, call.end() + len(args))
            if loop and re.search(rf"\b{loop.group(1)}\b", args):
                names |= tuples.get(loop.group(2), set())
            before = src[max(0, call.start() - 300) : call.start()]
            names |= {
                name for var, name in _ALIAS.findall(before) if re.search(rf"\b{var}\b", args)
            }
            for name in names & set(TOPICS):
                found[name].add(str(file.relative_to(REPO)))
    return found


PUBLISHED = {process: published_topics(paths) for process, paths in SOURCES.items()}


def test_every_named_process_has_sources():
    named = {p for topic in TOPICS.values() for p in topic.publishers}
    assert named <= set(SOURCES), f"add to SOURCES: {sorted(named - set(SOURCES))}"
    for paths in SOURCES.values():
        assert paths and all(p.exists() for p in paths)


@pytest.mark.parametrize(
    ("name", "process"),
    [(name, p) for name, topic in TOPICS.items() for p in topic.publishers],
)
def test_each_declared_publisher_declares_the_topic(name, process):
    if name in PUBLISHED[process]:
        return
    paths = SOURCES[process]
    uses_sdk = any(c in _code(f) for f in _files(paths) for c in SDK_COMMANDERS)
    assert process in COMMANDS_THROUGH_THE_SDK and uses_sdk and name in PUBLISHED["sdk"], (
        f"the registry says {process} publishes {name} ({TOPICS[name].template}), "
        f"but no publisher of it is declared in {[str(p.relative_to(REPO)) for p in paths]}"
    )


@pytest.mark.parametrize("process", sorted(set(SOURCES) - {"tests"}))
def test_no_process_publishes_what_the_registry_does_not_say(process):
    undeclared = {
        name: sorted(files)
        for name, files in PUBLISHED[process].items()
        if process not in TOPICS[name].publishers
        and not (process == "bridge_tello" and "bridge" in TOPICS[name].publishers)
        and not (process == "bridge" and "bridge_tello" in TOPICS[name].publishers)
    }
    assert undeclared == {}, f"{process} publishes topics the registry does not list it for"
