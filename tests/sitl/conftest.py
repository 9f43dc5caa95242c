"""Opt-in tier: flights against real ArduCopter SITL (an ArduPilot build of our own).

These tests run only when ``DRONEWRAPPER_ARDUPILOT_SITL`` names an ``arducopter`` SITL binary
(``<ardupilot>/build/sitl/bin/arducopter``; how to build one: docs/ardupilot.md). Without it
they are deselected, and the run says so with the reason: CI cannot build ArduPilot (its
sources are not on a package registry), so they are never a silent pass.
"""

from __future__ import annotations

import pytest
from ardupilot_sitl import ENV, sitl_binary

MARKER = "ardupilot_sitl"
_deselected: list[str] = []


def pytest_configure(config: pytest.Config) -> None:
    config.addinivalue_line(
        "markers", f"{MARKER}: flies real ArduCopter SITL (opt-in: set {ENV}=path/to/arducopter)"
    )


def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    if sitl_binary() is not None:
        return
    kept = [item for item in items if item.get_closest_marker(MARKER) is None]
    dropped = [item for item in items if item.get_closest_marker(MARKER) is not None]
    if dropped:
        config.hook.pytest_deselected(items=dropped)
        items[:] = kept
        _deselected[:] = [item.nodeid for item in dropped]


def pytest_terminal_summary(terminalreporter, exitstatus: int, config: pytest.Config) -> None:
    if _deselected:
        terminalreporter.write_line(
            f"{len(_deselected)} ArduCopter SITL test(s) deselected: {ENV} is not set "
            f"(opt-in; set it to an arducopter SITL binary, see docs/ardupilot.md)",
            yellow=True,
        )
