"""Where the opt-in tier finds real firmware: ``PX4_SITL_DIR`` names a PX4-Autopilot tree (or
its ``build/px4_sitl_default``) built for SITL, ``AP_SITL_DIR`` an ArduPilot tree with
``build/sitl/bin/arducopter``. Unset, the tier's tests are deselected (conftest.py). Starting a
build is dronewrapper_sim.external.firmware's."""

from __future__ import annotations

import contextlib
import os
from pathlib import Path

import pytest

from dronewrapper_sim.external.firmware import arducopter, px4_sih

PX4_ENV = "PX4_SITL_DIR"
AP_ENV = "AP_SITL_DIR"
AUTOPILOTS = [
    pytest.param("px4", marks=pytest.mark.px4_sih),
    pytest.param("ardupilot", marks=pytest.mark.ap_sitl),
]
"""Both firmwares as a test's ``autopilot`` parameter, each marked so that the tier's conftest
deselects it where its tree is not given."""


def _dir(env: str) -> Path | None:
    value = os.environ.get(env, "").strip()
    return Path(value).expanduser() if value else None


def px4_dir() -> Path | None:
    """The PX4 tree ``PX4_SITL_DIR`` names (None: tier off)."""
    return _dir(PX4_ENV)


def ardupilot_dir() -> Path | None:
    """The ArduPilot tree ``AP_SITL_DIR`` names (None: tier off)."""
    return _dir(AP_ENV)


def start(
    autopilot: str, workdir: Path, serial: tuple[str, int] | None = None
) -> contextlib.AbstractContextManager:
    """The firmware of ``autopilot`` (``px4``: PX4 SIH, ``ardupilot``: ArduCopter) from the
    tree its variable names, running in ``workdir`` until the context ends; ``serial`` (device,
    baud): its MAVLink on that serial device too (see dronewrapper_sim.external.firmware)."""
    if autopilot == "px4":
        return px4_sih(px4_dir(), workdir, serial=serial)
    return arducopter(ardupilot_dir(), workdir, serial=serial)
