"""The checks every bridge applies to a flight request (take-off, landing, go-to), the typed
failure it answers with, where a take-off climbs to (:func:`takeoff_heights`, :func:`took_off`)
and where a go-to flies (:func:`goto_target`).

A request field is a number sent by any commander: it must be finite and inside the range the
call allows, or the call is refused with ``ValueError`` naming the field (the node answers it
as a bad request, nothing is sent to the aircraft).
"""

from __future__ import annotations

import math
from typing import Protocol

from dronewrapper import envelope as env
from dronewrapper.envelope import Envelope, EnvelopeError
from dronewrapper.geodesy import to_enu
from dronewrapper.msgs.flight import NO_HOME, REFUSED, FlightResult, GotoRequest
from dronewrapper.msgs.mavros import LANDED_STATE_ON_GROUND, LANDED_STATE_UNDEFINED
from dronewrapper_bridge_base.frames import yaw_enu_to_ned


class HomeHolder(Protocol):
    """What a bridge's mission state holds of home and its envelope."""

    envelope: Envelope
    home_local: tuple[float, float, float]  # home in the autopilot's local frame (ENU m)
    home_geo: tuple[float, float, float] | None  # (latitude deg, longitude deg, altitude m)


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


def land_point(latitude: float, longitude: float) -> tuple[float, float]:
    """A landing request's (latitude, longitude) in degrees, each within its bounds or NaN
    (NaN: where the aircraft is); ValueError naming the bad one."""
    for name, value, bound in (("latitude", latitude, 90.0), ("longitude", longitude, 180.0)):
        if not math.isnan(value) and not (math.isfinite(value) and abs(value) <= bound):
            raise ValueError(f"{name} must be within ±{bound:g} degrees or NaN, got {value!r}")
    return latitude, longitude


def takeoff_command(height: float, yaw: float) -> tuple[float, float]:
    """A TAKEOFF service request's (altitude m above the take-off point, yaw rad ENU), each
    checked (altitude in (0, 1000] or NaN, yaw finite or NaN; ValueError naming the bad one),
    as (altitude m, yaw in degrees NED) for the autopilot's NAV_TAKEOFF (NaN: its default)."""
    if not math.isnan(height) and not (math.isfinite(height) and 0.0 < height <= 1000.0):
        raise ValueError(f"altitude must be in (0, 1000] m or NaN, got {height!r}")
    if not (math.isnan(yaw) or math.isfinite(yaw)):
        raise ValueError(f"yaw must be finite or NaN, got {yaw!r}")
    return height, math.nan if math.isnan(yaw) else math.degrees(yaw_enu_to_ned(yaw))


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


def takeoff_heights(z0: float, landed_state: int, height: float) -> tuple[float, float]:
    """A take-off's (start z, target z), local ENU m: from the aircraft's z ``z0`` when on the
    ground (or its landed state is unknown), from the local origin when caught in the air
    mid-landing; the target ``height`` m above the start."""
    on_ground = landed_state in (LANDED_STATE_ON_GROUND, LANDED_STATE_UNDEFINED)
    start_z = z0 if on_ground else 0.0
    return start_z, start_z + height


def took_off(z: float, start_z: float, height: float) -> FlightResult:
    """A take-off's success: the aircraft at local z ``z`` (m, NaN: unknown), ``start_z`` the
    take-off point's, ``height`` m asked."""
    return FlightResult(
        success=True,
        message=f"took off: {z - start_z:.2f} m above the take-off point ({height:g} m asked)",
        height=z - start_z,
    )


def goto_target(
    state: HomeHolder, request: GotoRequest
) -> tuple[float, float, float] | FlightResult:
    """Where a go-to flies (local ENU m): ``request``'s x, y, z from home, or its latitude and
    longitude made relative to home; or the FlightResult refusing it (``no_home``: a
    geodetic request while home has no latitude and longitude; ``refused``: the point is
    outside ``state.envelope``)."""
    if request.geodetic:
        if state.home_geo is None or math.isnan(state.home_geo[0]):
            return failed(NO_HOME, "home has no latitude and longitude (no GPS): go to x, y")
        east, north = to_enu(state.home_geo, request.latitude, request.longitude)
    else:
        east, north = request.x, request.y
    try:
        env.check_position(state.envelope, east, north, request.z)
    except EnvelopeError as exc:
        return failed(REFUSED, f"goto refused: {exc}", "goto")
    hx, hy, hz = state.home_local
    return (hx + east, hy + north, hz + request.z)
