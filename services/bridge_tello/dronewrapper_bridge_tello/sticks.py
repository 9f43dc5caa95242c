"""PositionTarget (ENU / FLU, DESIGN's three controls) -> the Tello's ``rc a b c d`` sticks.

The Tello's sticks: ``a`` roll (> 0 right), ``b`` pitch (> 0 forward), ``c`` throttle (> 0 up),
``d`` yaw (> 0 clockwise), integers in -100..100. We speak FLU and CCW, so::

    a = -vy * horizontal_scale    (vy > 0 is left)
    b =  vx * horizontal_scale
    c =  vz * vertical_scale
    d = -yaw_rate * yaw_scale     (yaw_rate > 0 is counter-clockwise)

Scales are stick units per m/s (per rad/s for yaw), calibrated per aircraft in the config; the
results are rounded and clamped to ``max_stick``.

Controls accepted (type_mask, coordinate_frame), validated like bridge_mavlink's:

* 1991 in frame 8: body velocity (FLU m/s) + yaw rate; in frame 1 the velocity is local ENU
  and is turned into body axes with the current heading.
* 1987: body vx, vy + altitude z (ENU m) + yaw rate: the altitude is held by closing the loop
  on the estimated height (vz = ``kp_z`` x error, clamped).
* 3064 in frame 1: position x, y, z (ENU m) + yaw: flown by closing the loop on the
  dead-reckoned pose (P control, speeds clamped), so it is as good as that estimate.
"""

from __future__ import annotations

import math
from typing import Annotated

import msgspec

from dronewrapper.msgs.mavros import (
    FRAME_LOCAL_NED,
    PositionTarget,
)
from dronewrapper.runtime.config_ranges import check_ranges
from dronewrapper_bridge_base import setpoint_limits
from dronewrapper_bridge_base.setpoint_limits import Kind, SetpointError
from dronewrapper_bridge_tello.frames import Vec3, enu_to_heading_flu, wrap_pi

Sticks = tuple[int, int, int, int]
STOP: Sticks = (0, 0, 0, 0)


class StickScale(msgspec.Struct, frozen=True, kw_only=True, forbid_unknown_fields=True):
    """Calibration and limits of the velocity -> stick mapping (also the ``scale`` section of
    the bridge's config, as is).

    Attributes:
        horizontal: stick units per m/s forward/sideways (100 ~ 1 m/s on a Tello).
        vertical: stick units per m/s up/down.
        yaw: stick units per rad/s of yaw rate.
        max_stick: clamp of every stick (the SDK allows 100).
        max_horizontal_speed, max_vertical_speed, max_yaw_rate: setpoints beyond these are
            refused (m/s, rad/s).
        max_distance, min_altitude, max_altitude: bounds of position targets (m).
        kp_xy, kp_z, kp_yaw: position loop gains (1/s).
        position_speed, position_climb, position_yaw_rate: speed limits of the position loop.
    """

    horizontal: float = 100.0
    vertical: float = 100.0
    yaw: float = 57.0
    max_stick: Annotated[int, msgspec.Meta(ge=1, le=100)] = 100
    max_horizontal_speed: float = 3.0
    max_vertical_speed: float = 2.0
    max_yaw_rate: float = 2.0 * math.pi
    max_distance: float = 100.0
    min_altitude: float = 0.0
    max_altitude: float = 30.0
    kp_xy: float = 0.8
    kp_z: float = 1.0
    kp_yaw: float = 1.5
    position_speed: float = 0.6
    position_climb: float = 0.5
    position_yaw_rate: float = 1.0

    def __post_init__(self) -> None:
        check_ranges(self, "scale.")


def validate(target: PositionTarget, scale: StickScale) -> Kind:
    """The control ``target`` asks for, or SetpointError saying what is wrong with it (the
    rules every bridge shares: :mod:`dronewrapper_bridge_base.setpoint_limits`)."""
    return setpoint_limits.validate(target, scale)


def _clamp(value: float, limit: float) -> float:
    return max(-limit, min(limit, value))


def sticks_from_flu(vx: float, vy: float, vz: float, yaw_rate: float, scale: StickScale) -> Sticks:
    """Body FLU velocity (m/s) and CCW yaw rate (rad/s) as clamped ``rc a b c d`` integers."""
    limit = scale.max_stick

    def stick(value: float) -> int:
        return round(_clamp(value, limit))

    return (
        stick(-vy * scale.horizontal),
        stick(vx * scale.horizontal),
        stick(vz * scale.vertical),
        stick(-yaw_rate * scale.yaw),
    )


def body_velocity(
    target: PositionTarget, kind: Kind, position: Vec3, yaw: float, scale: StickScale
) -> tuple[float, float, float, float]:
    """(vx, vy, vz FLU m/s, yaw_rate rad/s) that fly a valid ``target`` from the current pose.

    ``position`` is the estimated ENU position (m), ``yaw`` the ENU heading (rad).
    """
    if kind is Kind.POSITION:
        p = target.required_position()
        east = scale.kp_xy * (p.x - position[0])
        north = scale.kp_xy * (p.y - position[1])
        speed = math.hypot(east, north)
        if speed > scale.position_speed:
            east, north = east * scale.position_speed / speed, north * scale.position_speed / speed
        forward, left = enu_to_heading_flu(east, north, yaw)
        climb = _clamp(scale.kp_z * (p.z - position[2]), scale.position_climb)
        turn = _clamp(scale.kp_yaw * wrap_pi(target.yaw - yaw), scale.position_yaw_rate)
        return forward, left, climb, turn
    v = target.velocity
    if target.coordinate_frame == FRAME_LOCAL_NED:
        forward, left = enu_to_heading_flu(v.x, v.y, yaw)
    else:
        forward, left = v.x, v.y
    if kind is Kind.MIXED:
        climb = _clamp(
            scale.kp_z * (target.required_position().z - position[2]), scale.position_climb
        )
    else:
        climb = v.z
    return forward, left, climb, target.yaw_rate


def rc_command(sticks: Sticks) -> str:
    """The SDK text for ``sticks``."""
    a, b, c, d = sticks
    return f"rc {a} {b} {c} {d}"


__all__ = [
    "STOP",
    "Kind",
    "SetpointError",
    "StickScale",
    "Sticks",
    "body_velocity",
    "rc_command",
    "sticks_from_flu",
    "validate",
]
