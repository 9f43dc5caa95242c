"""PX4 flight modes as carried in HEARTBEAT ``custom_mode`` (main << 16 | sub << 24).

Names follow pymavlink's PX4 mode map ("OFFBOARD", "LOITER", ...); MAVROS names
("AUTO.LOITER", ...) are accepted as aliases by :func:`from_name`.
"""

from __future__ import annotations

from enum import Enum

MAIN_MANUAL = 1
MAIN_ALTCTL = 2
MAIN_POSCTL = 3
MAIN_AUTO = 4
MAIN_ACRO = 5
MAIN_OFFBOARD = 6
MAIN_STABILIZED = 7

SUB_AUTO_READY = 1
SUB_AUTO_TAKEOFF = 2
SUB_AUTO_LOITER = 3
SUB_AUTO_MISSION = 4
SUB_AUTO_RTL = 5
SUB_AUTO_LAND = 6
SUB_AUTO_FOLLOW_TARGET = 8
SUB_AUTO_PRECLAND = 9


class Mode(Enum):
    """A PX4 navigation mode: value = (main mode, sub mode)."""

    MANUAL = (MAIN_MANUAL, 0)
    ALTCTL = (MAIN_ALTCTL, 0)
    POSCTL = (MAIN_POSCTL, 0)
    ACRO = (MAIN_ACRO, 0)
    STABILIZED = (MAIN_STABILIZED, 0)
    OFFBOARD = (MAIN_OFFBOARD, 0)
    TAKEOFF = (MAIN_AUTO, SUB_AUTO_TAKEOFF)
    LOITER = (MAIN_AUTO, SUB_AUTO_LOITER)
    MISSION = (MAIN_AUTO, SUB_AUTO_MISSION)
    RTL = (MAIN_AUTO, SUB_AUTO_RTL)
    LAND = (MAIN_AUTO, SUB_AUTO_LAND)
    FOLLOWME = (MAIN_AUTO, SUB_AUTO_FOLLOW_TARGET)
    PRECLAND = (MAIN_AUTO, SUB_AUTO_PRECLAND)

    @property
    def main(self) -> int:
        return self.value[0]

    @property
    def sub(self) -> int:
        return self.value[1]

    @property
    def custom_mode(self) -> int:
        """The HEARTBEAT custom_mode of this mode."""
        return encode(self.main, self.sub)

    @property
    def mavros_name(self) -> str:
        """The name MAVROS uses (``AUTO.LOITER``, ``OFFBOARD``, ...)."""
        return f"AUTO.{self.name}" if self.main == MAIN_AUTO else self.name

    @property
    def needs_rc(self) -> bool:
        """Manual modes need a manual control input (RC or joystick)."""
        return self.main in (MAIN_MANUAL, MAIN_ALTCTL, MAIN_POSCTL, MAIN_ACRO, MAIN_STABILIZED)


_MAVROS_ALIASES = {"AUTO.RTL": "RTL", "AUTO.LAND": "LAND", "AUTO.LOITER": "LOITER"}


def encode(main: int, sub: int = 0) -> int:
    """custom_mode for ``main``/``sub`` modes."""
    return (int(main) & 0xFF) << 16 | (int(sub) & 0xFF) << 24


def decode(custom_mode: int) -> tuple[int, int]:
    """(main, sub) from a HEARTBEAT custom_mode."""
    return (custom_mode >> 16) & 0xFF, (custom_mode >> 24) & 0xFF


def from_main_sub(main: int, sub: int) -> Mode | None:
    """The Mode for a DO_SET_MODE main/sub pair, or None if PX4 has no such mode.

    Like PX4, a non-AUTO main mode ignores the sub mode.
    """
    for mode in Mode:
        if mode.main == main and (main != MAIN_AUTO or mode.sub == sub):
            return mode
    return None


def from_custom_mode(custom_mode: int) -> Mode | None:
    """The Mode of a HEARTBEAT custom_mode, or None."""
    return from_main_sub(*decode(custom_mode))


def from_name(name: str) -> Mode | None:
    """The Mode named ``name`` (pymavlink or MAVROS spelling, case-insensitive), or None."""
    key = name.strip().upper()
    key = _MAVROS_ALIASES.get(key, key.removeprefix("AUTO."))
    return Mode.__members__.get(key)


NAV_NAMES = {
    Mode.MANUAL: "Manual",
    Mode.ALTCTL: "Altitude",
    Mode.POSCTL: "Position",
    Mode.ACRO: "Acro",
    Mode.STABILIZED: "Stabilized",
    Mode.OFFBOARD: "Offboard",
    Mode.TAKEOFF: "Takeoff",
    Mode.LOITER: "Hold",
    Mode.MISSION: "Mission",
    Mode.RTL: "Return",
    Mode.LAND: "Land",
    Mode.FOLLOWME: "Follow Target",
    Mode.PRECLAND: "Precision Land",
}
"""PX4's human names of the navigation states (as its status texts write them)."""
