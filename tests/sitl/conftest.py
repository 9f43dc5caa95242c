"""Opt-in tier: flights against real ArduCopter SITL (an ArduPilot build of our own).

These tests run only when ``DRONEWRAPPER_ARDUPILOT_SITL`` names an ``arducopter`` SITL binary
(``<ardupilot>/build/sitl/bin/arducopter``; how to build one: docs/ardupilot.md). Without it
they are deselected, and the run says so with the reason: CI cannot build ArduPilot (its
sources are not on a package registry), so they are never a silent pass.
"""

from __future__ import annotations

import sys
from pathlib import Path

import pytest
from ardupilot_sitl import ENV, sitl_binary

sys.path.append(str(Path(__file__).parents[1] / "scenario"))  # the scenario tier's flight helper

from firmware import AP_ENV, PX4_ENV, ardupilot_dir, px4_dir
from px4_zenoh_sitl import zenoh_build

MARKER = "ardupilot_sitl"
_deselected: list[str] = []
# the world-around-real-firmware flights: marker -> (variable, is it set)
FIRMWARE_MARKERS = {
    "px4_sih": (PX4_ENV, lambda: px4_dir() is not None),
    "ap_sitl": (AP_ENV, lambda: ardupilot_dir() is not None),
    "px4_zenoh": (PX4_ENV, lambda: zenoh_build() is not None),  # a px4_sitl_zenoh build
}
_firmware_deselected: dict[str, list[str]] = {}


def pytest_configure(config: pytest.Config) -> None:
    config.addinivalue_line(
        "markers", f"{MARKER}: flies real ArduCopter SITL (opt-in: set {ENV}=path/to/arducopter)"
    )
    for marker, (env, _) in FIRMWARE_MARKERS.items():
        config.addinivalue_line(
            "markers", f"{marker}: flies real firmware in our world (opt-in: set {env})"
        )


def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    for marker, (_env, enabled) in FIRMWARE_MARKERS.items():
        if enabled():
            continue
        dropped = [item for item in items if item.get_closest_marker(marker) is not None]
        if dropped:
            config.hook.pytest_deselected(items=dropped)
            items[:] = [item for item in items if item.get_closest_marker(marker) is None]
            _firmware_deselected[marker] = [item.nodeid for item in dropped]
    if sitl_binary() is not None:
        return
    kept = [item for item in items if item.get_closest_marker(MARKER) is None]
    dropped = [item for item in items if item.get_closest_marker(MARKER) is not None]
    if dropped:
        config.hook.pytest_deselected(items=dropped)
        items[:] = kept
        _deselected[:] = [item.nodeid for item in dropped]


def pytest_terminal_summary(terminalreporter, exitstatus: int, config: pytest.Config) -> None:
    for marker, nodeids in _firmware_deselected.items():
        env = FIRMWARE_MARKERS[marker][0]
        terminalreporter.write_line(
            f"{len(nodeids)} {marker} test(s) deselected: {env} is not set (opt-in; set it to "
            f"a firmware tree built for SITL, see docs/sitl_world.md)",
            yellow=True,
        )
    if _deselected:
        terminalreporter.write_line(
            f"{len(_deselected)} ArduCopter SITL test(s) deselected: {ENV} is not set "
            f"(opt-in; set it to an arducopter SITL binary, see docs/ardupilot.md)",
            yellow=True,
        )
