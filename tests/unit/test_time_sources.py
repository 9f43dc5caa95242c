"""The services, the simulator and compose read time from a clock object, never bare ``time``.

A process's time is its node's clock (``node.clock``: real in production, a fake bus's virtual
time in tests), so a bare ``time.time()``, ``time.monotonic()`` or ``time.sleep()`` (or the
function itself handed on, or imported by name) in their code is a place a test cannot inject
time. The few that must stay on the real clock are listed in :data:`ALLOWED`, each with how many
and why. ``time.perf_counter`` (CPU costs) and the formatting functions (``strftime``) are free.
"""

from __future__ import annotations

import ast
import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
SCANNED = ("services", "sim", "compose")
BARE = frozenset({"time", "monotonic", "sleep", "time_ns", "monotonic_ns"})
MAYBE = re.compile(r"\bimport time\b|\bfrom time import\b")
"""A file that imports no ``time`` has nothing to parse (most do not)."""

ALLOWED: dict[str, tuple[int, str]] = {
    "services/bridge_mavlink/dronewrapper_bridge_mavlink/provision.py": (
        5,
        "a one-shot command, no node: its deadlines bound pymavlink's blocking reads from "
        "real hardware, and the signing key's first timestamp is the real wall clock",
    ),
    "services/ground_station/dronewrapper_ground_station/server.py": (
        3,
        "waits, in real time, for uvicorn's real HTTP socket to be listening",
    ),
    "sim/dronewrapper_sim/serial_relay.py": (
        3,
        "a serial line emulated between a pseudo-terminal and a socket: byte timing against "
        "real file descriptors (select), not a node",
    ),
    "sim/dronewrapper_sim/external/firmware.py": (
        3,
        "starts real firmware, no node: retries PX4's MAVLink start, in real time, while the "
        "real PX4 process boots",
    ),
    "compose/dronewrapper_compose/launcher.py": (
        6,
        "supervises real OS processes (readiness deadlines, the run's duration)",
    ),
    "compose/dronewrapper_compose/demo.py": (
        6,
        "the demo's console: prints elapsed real time and paces its report for a person",
    ),
}
"""Files that keep bare real-time calls: path -> (how many, why)."""


def bare_time_uses(source: str) -> list[int]:
    """Line numbers of bare ``time`` reads and waits in ``source``: ``time.X`` (a call or
    the function handed on) with X in :data:`BARE`, and ``from time import X``."""
    tree = ast.parse(source)
    aliases = {"time"}
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            aliases |= {a.asname for a in node.names if a.name == "time" and a.asname}
    lines = []
    for node in ast.walk(tree):
        if (
            isinstance(node, ast.Attribute)
            and node.attr in BARE
            and isinstance(node.value, ast.Name)
            and node.value.id in aliases
        ):
            lines.append(node.lineno)
        elif isinstance(node, ast.ImportFrom) and node.module == "time":
            lines += [node.lineno for a in node.names if a.name in BARE]
    return sorted(lines)


def scanned_files() -> list[Path]:
    return [
        path
        for top in SCANNED
        for path in sorted((ROOT / top).rglob("*.py"))
        if "tests" not in path.relative_to(ROOT).parts and ".venv" not in path.parts
    ]


def test_the_scan_finds_every_form():
    source = (
        "import time\nimport time as _t\nfrom time import monotonic, perf_counter\n"
        "a = time.time()\nb = _t.sleep(1)\nc = f(clock=time.monotonic)\n"
        "d = time.perf_counter()\ne = time.strftime('%H')\nf = self.time.time()\n"
    )
    assert bare_time_uses(source) == [3, 4, 5, 6]


def test_services_sim_and_compose_read_time_from_a_clock():
    found = {}
    for path in scanned_files():
        source = path.read_text(encoding="utf-8")
        uses = bare_time_uses(source) if MAYBE.search(source) else []
        if uses:
            found[path.relative_to(ROOT).as_posix()] = uses
    unexpected = {
        name: lines
        for name, lines in found.items()
        if name not in ALLOWED or len(lines) > ALLOWED[name][0]
    }
    assert not unexpected, (
        "bare time.time/monotonic/sleep (read the node's clock, node.clock, instead; or list "
        f"the file in ALLOWED with its reason): {unexpected}"
    )
    stale = {name for name, (count, _) in ALLOWED.items() if len(found.get(name, [])) < count}
    assert not stale, f"fewer bare uses than ALLOWED says: lower the counts of {sorted(stale)}"


def test_every_allowance_gives_its_reason():
    assert all(count > 0 and len(why) > 20 for count, why in ALLOWED.values())
