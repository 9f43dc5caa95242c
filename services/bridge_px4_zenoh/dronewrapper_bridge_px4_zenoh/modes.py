"""PX4's navigation states (``VehicleStatus.nav_state``) as the mode names MAVROS shows, and back.

Over Zenoh a mode is asked for with ``VEHICLE_CMD_SET_NAV_STATE`` (param1 = the nav state), the
command PX4's commander keeps for ROS; MAVLink's main/sub custom modes are not involved. A state
without a MAVROS name of its own shows as the mode PX4's MAVLink module reports for it
(``DESCEND`` as ``AUTO.LAND``, ``POSITION_SLOW`` as ``POSCTL``).
"""

from __future__ import annotations

NAV_STATE_OF_MODE: dict[str, int] = {
    "MANUAL": 0,
    "ALTCTL": 1,
    "POSCTL": 2,
    "AUTO.MISSION": 3,
    "AUTO.LOITER": 4,
    "AUTO.RTL": 5,
    "ACRO": 10,
    "OFFBOARD": 14,
    "STABILIZED": 15,
    "AUTO.TAKEOFF": 17,
    "AUTO.LAND": 18,
    "AUTO.FOLLOW_TARGET": 19,
    "AUTO.PRECLAND": 20,
}
"""A mode that can be asked for, by MAVROS name -> nav state."""

_SHOWN_AS = {
    6: "POSCTL",
    8: "ALTCTL",
    12: "AUTO.LAND",
    13: "MANUAL",
    21: "POSCTL",
    22: "AUTO.TAKEOFF",
}
MODE_OF_NAV_STATE: dict[int, str] = {
    **{state: name for name, state in NAV_STATE_OF_MODE.items()},
    **_SHOWN_AS,
}
"""Every nav state PX4 reports -> the MAVROS mode name shown for it."""

GUIDED_MODES = frozenset({"OFFBOARD"})
"""Modes in which PX4 flies the bridge's setpoints."""
MANUAL_INPUT_MODES = frozenset({"MANUAL", "ALTCTL", "POSCTL", "ACRO", "STABILIZED"})
"""Modes in which a pilot's sticks drive the aircraft."""


def mode_name(nav_state: int) -> str:
    """The MAVROS name of a nav state (``EXTERNAL3`` style for an external mode, ``NAV_STATE_n``
    for one this table does not know)."""
    if nav_state in MODE_OF_NAV_STATE:
        return MODE_OF_NAV_STATE[nav_state]
    if 23 <= nav_state <= 30:
        return f"EXTERNAL{nav_state - 22}"
    return f"NAV_STATE_{nav_state}"


def nav_state_of(mode: str) -> int:
    """The nav state to ask for a mode named as MAVROS does (case-insensitive).

    Raises:
        ValueError: PX4 has no such mode to ask for (the message lists those it has).
    """
    key = mode.strip().upper()
    if key not in NAV_STATE_OF_MODE:
        raise ValueError(f"PX4 has no mode {mode!r}; modes: {', '.join(NAV_STATE_OF_MODE)}")
    return NAV_STATE_OF_MODE[key]
