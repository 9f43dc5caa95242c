"""Validation of what a page asks for (pure). Every field is required, finite and in range;
a bad request raises :class:`BadRequest` naming the field, and nothing is sent."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

from dronewrapper_ground_station.config import TeleopLimits


class BadRequest(ValueError):
    """A request field is missing, not a number, not finite or out of range."""


def number(data: Any, key: str, lo: float, hi: float) -> float:
    """``data[key]`` as a finite float in ``[lo, hi]``.

    Raises:
        BadRequest: ``data`` is not an object, or the field is missing or out of range.
    """
    if not isinstance(data, dict):
        raise BadRequest(f"expected a JSON object, got {type(data).__name__}")
    if key not in data:
        raise BadRequest(f"{key} is required")
    value = data[key]
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise BadRequest(f"{key} must be a number, got {value!r}")
    value = float(value)
    if not math.isfinite(value) or not lo <= value <= hi:
        raise BadRequest(f"{key} must be finite and in [{lo:g}, {hi:g}], got {value}")
    return value


def text(data: Any, key: str, max_len: int = 64) -> str:
    """``data[key]`` as a non-empty printable string of at most ``max_len`` characters."""
    if not isinstance(data, dict):
        raise BadRequest(f"expected a JSON object, got {type(data).__name__}")
    value = data.get(key)
    if not isinstance(value, str) or not value.strip() or len(value) > max_len:
        raise BadRequest(f"{key} must be a non-empty string of at most {max_len} characters")
    if not value.isprintable():
        raise BadRequest(f"{key} must be printable")
    return value.strip()


@dataclass(frozen=True)
class VelocityCommand:
    """A teleop command, body FLU: forward, left, up (m/s) and yaw rate (rad/s, CCW +)."""

    vx: float
    vy: float
    vz: float
    yaw_rate: float


def sticks(data: Any, limits: TeleopLimits) -> VelocityCommand:
    """Stick deflections (each in [-1, 1]) scaled by the teleop limits.

    ``forward``: + forward; ``left``: + left; ``up``: + climb; ``turn``: + counter-clockwise.
    """
    return VelocityCommand(
        vx=number(data, "forward", -1, 1) * limits.horizontal,
        vy=number(data, "left", -1, 1) * limits.horizontal,
        vz=number(data, "up", -1, 1) * limits.vertical,
        yaw_rate=number(data, "turn", -1, 1) * limits.yaw_rate,
    )


def goto(data: Any, max_distance: float) -> tuple[float, float]:
    """A map click: local ENU ``x``, ``y`` (m), each within ``max_distance`` of the origin."""
    return number(data, "x", -max_distance, max_distance), number(
        data, "y", -max_distance, max_distance
    )


def object_velocity(data: Any, speed: float) -> tuple[float, float]:
    """A simulated object's keyboard command: ``east``, ``north`` in [-1, 1] times ``speed``."""
    return number(data, "east", -1, 1) * speed, number(data, "north", -1, 1) * speed


def scenario_name(data: Any) -> str:
    """The ``scenario`` to load in the simulator (the simulator checks it is a known one)."""
    return text(data, "scenario")
