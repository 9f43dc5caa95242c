"""``VehicleCommand`` messages for PX4's ``/fmu/in/vehicle_command``, and what its acks say.

A command carries the target system and component PX4 answers for (1, 1 on a default
airframe), the bridge as its source (``from_external``: PX4 then treats it like a ground
station's), and ``timestamp`` in PX4's microseconds (PX4 overwrites it on arrival).
"""

from __future__ import annotations

import math
from typing import Any

ARM_DISARM = 400
NAV_TAKEOFF = 22
NAV_LAND = 21
NAV_RETURN_TO_LAUNCH = 20
SET_NAV_STATE = 100001

ACCEPTED, TEMPORARILY_REJECTED, DENIED, UNSUPPORTED, FAILED, IN_PROGRESS, CANCELLED = range(7)
RESULT_TEXT = {
    ACCEPTED: "accepted",
    TEMPORARILY_REJECTED: "temporarily rejected",
    DENIED: "denied",
    UNSUPPORTED: "unsupported",
    FAILED: "failed",
    IN_PROGRESS: "in progress",
    CANCELLED: "cancelled",
}

SOURCE_SYSTEM = 255
SOURCE_COMPONENT = 190  # MAV_COMP_ID_MISSIONPLANNER: PX4 treats it as a ground station's


def vehicle_command(
    command: int, *params: float, target_system: int = 1, target_component: int = 1
) -> dict[str, Any]:
    """A VehicleCommand value (``params``: param1.. in order, the rest NaN as PX4 reads
    "unset"; param5/param6 are latitude/longitude in degrees where a command takes them)."""
    values = [*params, *([math.nan] * (7 - len(params)))]
    if len(values) != 7:
        raise ValueError(f"a vehicle command has 7 params, got {len(params)}")
    return {
        "timestamp": 0,
        **{f"param{i + 1}": value for i, value in enumerate(values)},
        "command": command,
        "target_system": target_system,
        "target_component": target_component,
        "source_system": SOURCE_SYSTEM,
        "source_component": SOURCE_COMPONENT,
        "confirmation": 0,
        "from_external": True,
    }


def arm(value: bool, **target: int) -> dict[str, Any]:
    """Arm (True) or disarm (False)."""
    return vehicle_command(ARM_DISARM, 1.0 if value else 0.0, **target)


def set_nav_state(nav_state: int, **target: int) -> dict[str, Any]:
    """Ask for a navigation state (:mod:`.modes`)."""
    return vehicle_command(SET_NAV_STATE, float(nav_state), **target)


def result_text(result: int) -> str:
    """An ack's result as words (``result 9`` for one PX4 added later)."""
    return RESULT_TEXT.get(result, f"result {result}")
