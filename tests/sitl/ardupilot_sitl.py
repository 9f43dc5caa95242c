"""Where the opt-in ArduCopter SITL tier finds its firmware: the arducopter binary named by the
environment and the ArduPilot tree it was built in (the firmware itself is started by
:func:`dronewrapper_sim.external.firmware.arducopter`)."""

from __future__ import annotations

import os
from pathlib import Path

ENV = "DRONEWRAPPER_ARDUPILOT_SITL"  # names the arducopter binary; unset: tier deselected


def sitl_binary() -> Path | None:
    """The arducopter binary named by the environment, or None when the tier is off."""
    value = os.environ.get(ENV, "").strip()
    return Path(value).expanduser() if value else None


def sitl_tree(binary: Path) -> Path:
    """The ArduPilot tree ``binary`` was built in (``<tree>/build/sitl/bin/arducopter``)."""
    return binary.resolve().parents[3]
