"""Flight-mode names <-> MAVLink ``custom_mode`` for PX4 and ArduCopter, spelled as MAVROS does.

PX4 packs its mode in HEARTBEAT.custom_mode as ``main << 16 | sub << 24``; a mode change is
``MAV_CMD_DO_SET_MODE`` with param1 = MAV_MODE_FLAG_CUSTOM_MODE_ENABLED, param2 = main,
param3 = sub. ArduCopter uses a plain mode number (param2). Names are matched
case-insensitively; a few common aliases (``HOLD``, ``LAND``, ``RTL`` on PX4) are accepted.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

from pymavlink.dialects.v20.common import (
    MAV_AUTOPILOT_ARDUPILOTMEGA,
    MAV_AUTOPILOT_PX4,
    MAV_MODE_FLAG_CUSTOM_MODE_ENABLED,
)

from dronewrapper_bridge_base.guided_failsafe import GUIDED_MODES as GUIDED_MODES
from dronewrapper_bridge_base.guided_failsafe import holds_on_the_ground as holds_on_the_ground
from dronewrapper_bridge_base.guided_failsafe import is_guided as is_guided

AUTOPILOT_PX4 = "px4"
AUTOPILOT_ARDUPILOT = "ardupilotmega"


# PX4 main modes and AUTO sub modes (px4_custom_mode.h), names as MAVROS spells them.
PX4_MODES: dict[str, tuple[int, int]] = {
    "MANUAL": (1, 0),
    "ALTCTL": (2, 0),
    "POSCTL": (3, 0),
    "AUTO.READY": (4, 1),
    "AUTO.TAKEOFF": (4, 2),
    "AUTO.LOITER": (4, 3),
    "AUTO.MISSION": (4, 4),
    "AUTO.RTL": (4, 5),
    "AUTO.LAND": (4, 6),
    "AUTO.RTGS": (4, 7),
    "AUTO.FOLLOW_TARGET": (4, 8),
    "AUTO.PRECLAND": (4, 9),
    "ACRO": (5, 0),
    "OFFBOARD": (6, 0),
    "STABILIZED": (7, 0),
    "RATTITUDE": (8, 0),
}
PX4_ALIASES = {
    "HOLD": "AUTO.LOITER",
    "LOITER": "AUTO.LOITER",
    "LAND": "AUTO.LAND",
    "RTL": "AUTO.RTL",
    "TAKEOFF": "AUTO.TAKEOFF",
    "MISSION": "AUTO.MISSION",
    "POSITION": "POSCTL",
    "ALTITUDE": "ALTCTL",
    "FOLLOWME": "AUTO.FOLLOW_TARGET",
}

# ArduCopter flight modes (ArduCopter/mode.h), names as MAVROS spells them.
ARDUCOPTER_MODES: dict[str, int] = {
    "STABILIZE": 0,
    "ACRO": 1,
    "ALT_HOLD": 2,
    "AUTO": 3,
    "GUIDED": 4,
    "LOITER": 5,
    "RTL": 6,
    "CIRCLE": 7,
    "LAND": 9,
    "DRIFT": 11,
    "SPORT": 13,
    "FLIP": 14,
    "AUTOTUNE": 15,
    "POSHOLD": 16,
    "BRAKE": 17,
    "THROW": 18,
    "AVOID_ADSB": 19,
    "GUIDED_NOGPS": 20,
    "SMART_RTL": 21,
    "FLOWHOLD": 22,
    "FOLLOW": 23,
    "ZIGZAG": 24,
    "SYSTEMID": 25,
    "AUTOROTATE": 26,
    "AUTO_RTL": 27,
}
ARDUCOPTER_ALIASES = {"HOLD": "LOITER", "AUTO.LAND": "LAND", "AUTO.RTL": "RTL"}

# The mode in which each autopilot follows external setpoints.
GUIDED_MODE = {AUTOPILOT_PX4: "OFFBOARD", AUTOPILOT_ARDUPILOT: "GUIDED"}
# The mode the bridge asks for to land / return / hold, per autopilot.
LAND_MODE = {AUTOPILOT_PX4: "AUTO.LAND", AUTOPILOT_ARDUPILOT: "LAND"}
RETURN_MODE = {AUTOPILOT_PX4: "AUTO.RTL", AUTOPILOT_ARDUPILOT: "RTL"}
HOLD_MODE = {AUTOPILOT_PX4: "AUTO.LOITER", AUTOPILOT_ARDUPILOT: "LOITER"}


def autopilot_kind(mav_autopilot: int) -> str:
    """``px4``, ``ardupilotmega`` or ``generic`` from HEARTBEAT.autopilot (MAV_AUTOPILOT)."""
    if mav_autopilot == MAV_AUTOPILOT_PX4:
        return AUTOPILOT_PX4
    if mav_autopilot == MAV_AUTOPILOT_ARDUPILOTMEGA:
        return AUTOPILOT_ARDUPILOT
    return "generic"


def _px4_custom_mode(main: int, sub: int) -> int:
    return (main << 16) | (sub << 24)


_PX4_BY_VALUE = {_px4_custom_mode(*ms): name for name, ms in PX4_MODES.items()}
_ARDU_BY_VALUE = {number: name for name, number in ARDUCOPTER_MODES.items()}


def mode_name(autopilot: str, custom_mode: int) -> str:
    """The MAVROS name of HEARTBEAT.custom_mode (``CMODE(n)`` when unknown, like MAVROS)."""
    if autopilot == AUTOPILOT_ARDUPILOT:
        return _ARDU_BY_VALUE.get(custom_mode, f"CMODE({custom_mode})")
    main = (custom_mode >> 16) & 0xFF
    sub = (custom_mode >> 24) & 0xFF
    name = _PX4_BY_VALUE.get(_px4_custom_mode(main, sub if main == 4 else 0))
    return name or f"CMODE({custom_mode})"


def valid_modes(autopilot: str) -> list[str]:
    """The mode names accepted for ``autopilot``."""
    if autopilot == AUTOPILOT_ARDUPILOT:
        return list(ARDUCOPTER_MODES)
    return list(PX4_MODES)


def canonical_mode(autopilot: str, name: str) -> str:
    """The MAVROS spelling of ``name`` for ``autopilot`` (aliases resolved).

    Raises:
        ValueError: unknown mode; the message lists the valid names.
    """
    wanted = name.strip().upper() if isinstance(name, str) else ""
    table: Mapping[str, object]
    if autopilot == AUTOPILOT_ARDUPILOT:
        table, aliases = ARDUCOPTER_MODES, ARDUCOPTER_ALIASES
    else:
        table, aliases = PX4_MODES, PX4_ALIASES
    wanted = aliases.get(wanted, wanted)
    if wanted not in table and f"AUTO.{wanted}" in table:  # pymavlink's short PX4 names
        wanted = f"AUTO.{wanted}"
    if wanted not in table:
        kind = autopilot or AUTOPILOT_PX4
        raise ValueError(
            f"unknown mode {name!r} for {kind}; valid modes: {', '.join(valid_modes(autopilot))}"
        )
    return wanted


@dataclass(frozen=True)
class SetModeParams:
    """COMMAND_LONG params 1-3 of MAV_CMD_DO_SET_MODE for one mode."""

    name: str
    param1: float
    param2: float
    param3: float


def set_mode_params(autopilot: str, name: str) -> SetModeParams:
    """DO_SET_MODE parameters for mode ``name`` (raises ValueError if unknown)."""
    canonical = canonical_mode(autopilot, name)
    flag = float(MAV_MODE_FLAG_CUSTOM_MODE_ENABLED)
    if autopilot == AUTOPILOT_ARDUPILOT:
        return SetModeParams(canonical, flag, float(ARDUCOPTER_MODES[canonical]), 0.0)
    main, sub = PX4_MODES[canonical]
    return SetModeParams(canonical, flag, float(main), float(sub))
