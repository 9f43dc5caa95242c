"""The bridge's take-off and landing: one request each, answered when the manoeuvre has ended.

Each bridge flies them its own way (PX4: a primed setpoint stream, OFFBOARD, arm, climb;
ArduPilot: GUIDED, arm, NAV_TAKEOFF; Tello: ``takeoff``, then a move to the height), so a
client sends the same request to any aircraft. Heights in metres above the take-off point,
times in seconds.
"""

from __future__ import annotations

import math

import msgspec

REFUSED = "refused"
"""A step was refused (``step`` names it, ``result`` is its MAV_RESULT, -1: unanswered), or
the aircraft gave the manoeuvre up (disarmed, left the mode it was put in)."""
TOO_LATE = "too_late"
"""The manoeuvre's ``timeout`` passed first; the message names the altitude, mode and arming."""
NOT_READY = "not_ready"
"""Nothing to start from: the aircraft is not connected."""
NO_POSITION = "no_position"
"""No local position has arrived, so there is no point to take off from."""
CANCELLED = "cancelled"
"""A cancel request ended it (``{ns}/dronewrapper/cancel``): the aircraft holds where it is."""

FAILURES = (REFUSED, TOO_LATE, NOT_READY, NO_POSITION, CANCELLED)


class TakeoffRequest(msgspec.Struct, kw_only=True, forbid_unknown_fields=True, frozen=True):
    """Take off and climb to ``height`` m above the take-off point within ``timeout`` s;
    done within ``tolerance`` m of it. Already flying: nothing is done."""

    height: float
    timeout: float = 30.0
    tolerance: float = 0.1


class LandRequest(msgspec.Struct, kw_only=True, forbid_unknown_fields=True, frozen=True):
    """Land where the aircraft is; done once on the ground and disarmed, within ``timeout`` s."""

    timeout: float = 60.0


class CancelRequest(msgspec.Struct, kw_only=True, forbid_unknown_fields=True, frozen=True):
    """End the running take-off or landing at once; the aircraft holds where it is.
    ``reason`` (for the log, at most 200 characters) says why."""

    reason: str = ""

    def __post_init__(self) -> None:
        if not isinstance(self.reason, str) or len(self.reason) > 200:
            raise ValueError("reason must be a string of at most 200 characters")


class FlightResult(msgspec.Struct, kw_only=True, frozen=True):
    """How a take-off or landing ended.

    Attributes:
        success: it ended where asked (or nothing was needed: ``message`` says so).
        failure: ``""`` or one of :data:`FAILURES`.
        step: the step that was refused (``set_mode OFFBOARD``, ``arming``, ``takeoff`` ...).
        result: that step's MAV_RESULT (-1: no answer), None when none applies.
        message: what happened, for a person.
        height: the height reached above the take-off point (m), NaN when unknown.
    """

    success: bool = False
    failure: str = ""
    step: str = ""
    result: int | None = None
    message: str = ""
    height: float = math.nan
