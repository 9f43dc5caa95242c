"""Setpoint building: the paper's three controls as PositionTarget messages (pure functions).

Exactly docs/design.md's table ("PositionTarget semantics"):

=================  =========  =======================  =========================================
SDK call           type_mask  coordinate_frame         fields used
=================  =========  =======================  =========================================
``set_cmd_pos``    3064       FRAME_LOCAL_NED (1)      x, y, z (local ENU m), yaw (rad, ENU)
``set_cmd_vel``    1991       FRAME_BODY_NED (8)       vx, vy, vz (body FLU m/s), yaw_rate (rad/s)
``set_cmd_mix``    1987       FRAME_BODY_NED (8)       vx, vy (body FLU m/s), z (local ENU m),
                                                       yaw_rate (rad/s)
=================  =========  =======================  =========================================

The frame ids are MAVROS's names; the values are ENU/FLU as on MAVROS's topic side. Every
argument must be a finite real number: NaN, inf, bools, strings and None raise
:class:`~dronewrapper.errors.InvalidArgument` before anything is published, and so does a yaw or
yaw rate beyond a full turn (a value in degrees by mistake).
"""

from __future__ import annotations

import math
import numbers

from dronewrapper.errors import InvalidArgument
from dronewrapper.msgs import mavros
from dronewrapper.msgs.geometry import Point, Vector3
from dronewrapper.msgs.std import Header


def finite(name: str, value: object) -> float:
    """``value`` as a float if it is a finite real number (not a bool), else InvalidArgument."""
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise InvalidArgument(f"{name} must be a real number, got {type(value).__name__} {value!r}")
    number = float(value)
    if not math.isfinite(number):
        raise InvalidArgument(f"{name} must be finite, got {number!r}")
    return number


MAX_ANGLE_RAD = 2.0 * math.pi
"""Largest yaw (rad) or yaw rate (rad/s) accepted: beyond a full turn it is a degrees mistake."""


def radians(name: str, value: object, unit: str = "rad") -> float:
    """``value`` as a finite float within one turn (|value| <= 2 pi), else InvalidArgument.

    Angles are radians everywhere in the SDK; ``az=90`` is almost certainly meant in degrees,
    and the error says so instead of spinning the drone a quarter turn 14 times over.
    """
    number = finite(name, value)
    if abs(number) > MAX_ANGLE_RAD:
        raise InvalidArgument(
            f"{name}={number:g} {unit} is more than a full turn: angles are in radians "
            f"(did you mean math.radians({number:g}) = {math.radians(number):.3f}?)"
        )
    return number


def check_stamp(stamp: object, now: float) -> float:
    """The header stamp to use: ``now`` when ``stamp`` is None, else ``stamp`` if valid.

    A stamp is float seconds since the Unix epoch (a camera frame's ``header.stamp``); it must be
    finite and positive.
    """
    if stamp is None:
        return now
    value = finite("stamp", stamp)
    if value <= 0.0:
        raise InvalidArgument(f"stamp must be seconds since the Unix epoch (> 0), got {value!r}")
    return value


def position_target(
    x: float, y: float, z: float, yaw: float, *, stamp: float
) -> mavros.PositionTarget:
    """Position control: go to (x, y, z) in local ENU metres facing ``yaw`` (rad, ENU)."""
    return mavros.PositionTarget(
        header=Header(stamp=stamp, frame_id="map"),
        coordinate_frame=mavros.FRAME_LOCAL_NED,
        type_mask=mavros.MASK_POSITION,
        position=Point(x=finite("x", x), y=finite("y", y), z=finite("z", z)),
        yaw=radians("yaw", yaw),
    )


def velocity_target(
    vx: float, vy: float, vz: float, yaw_rate: float, *, stamp: float
) -> mavros.PositionTarget:
    """Velocity control: body FLU velocity (m/s) and yaw rate (rad/s, counter-clockwise +)."""
    return mavros.PositionTarget(
        header=Header(stamp=stamp, frame_id="base_link"),
        coordinate_frame=mavros.FRAME_BODY_NED,
        type_mask=mavros.MASK_VELOCITY,
        velocity=Vector3(x=finite("vx", vx), y=finite("vy", vy), z=finite("vz", vz)),
        yaw_rate=radians("az", yaw_rate, "rad/s"),
    )


def mixed_target(
    vx: float, vy: float, z: float, yaw_rate: float, *, stamp: float
) -> mavros.PositionTarget:
    """Mixed control: body FLU vx, vy (m/s), local ENU altitude z (m), yaw rate (rad/s)."""
    return mavros.PositionTarget(
        header=Header(stamp=stamp, frame_id="base_link"),
        coordinate_frame=mavros.FRAME_BODY_NED,
        type_mask=mavros.MASK_MIXED,
        position=Point(z=finite("z", z)),
        velocity=Vector3(x=finite("vx", vx), y=finite("vy", vy)),
        yaw_rate=radians("az", yaw_rate, "rad/s"),
    )
