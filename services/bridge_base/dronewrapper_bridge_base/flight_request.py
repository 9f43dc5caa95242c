"""The checks every bridge applies to a flight request (take-off, landing, go-to), and the
typed failure it answers with.

A request field is a number sent by any commander: it must be finite and inside the range the
call allows, or the call is refused with ``ValueError`` naming the field (the node answers it
as a bad request, nothing is sent to the aircraft).
"""

from __future__ import annotations

import math

from dronewrapper.msgs.flight import FlightResult


def checked(name: str, value: float, low: float, high: float) -> float:
    """``value`` if finite and in (``low``, ``high``]; ValueError naming ``name`` otherwise."""
    if not (isinstance(value, int | float) and math.isfinite(value) and low < value <= high):
        raise ValueError(f"{name} must be in ({low:g}, {high:g}], got {value!r}")
    return float(value)


def failed(failure: str, message: str, step: str = "", result: int | None = None) -> FlightResult:
    """A flight operation's answer when it did not succeed: ``failure`` is one of
    :data:`dronewrapper.msgs.flight.FAILURES`, ``step`` the step it stopped at, ``result`` the
    autopilot's result code when it gave one."""
    return FlightResult(success=False, failure=failure, step=step, result=result, message=message)


def takeoff_request(
    height: float, timeout: float, tolerance: float, max_height: float, max_timeout: float
) -> tuple[float, float, float]:
    """A take-off request's (height m, timeout s, tolerance m), each checked: height in
    (0, ``max_height``], timeout in (0, ``max_timeout``], tolerance in [0, height)."""
    height = checked("height", height, 0.0, max_height)
    timeout = checked("timeout", timeout, 0.0, max_timeout)
    if not (isinstance(tolerance, int | float) and 0.0 <= tolerance < height):
        raise ValueError(f"tolerance must be in [0, height), got {tolerance!r}")
    return height, timeout, float(tolerance)
