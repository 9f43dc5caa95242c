"""Motion models of world objects: pure, deterministic for a seed, time passed in.

Every model has ``advance(position, time_s, dt_s) -> (new_position, velocity)``: ENU m and m/s,
``time_s`` the world time at the start of the step. Random choices come from the
``numpy.random.Generator`` given at construction, so a seed fixes the whole trajectory.
"""

from __future__ import annotations

import math
from typing import Protocol

import numpy as np

from dronewrapper_sim.world.scenario import (
    CircleMotion,
    Motion,
    RandomWalkMotion,
    SmoothMotion,
    StaticMotion,
    TeleopMotion,
    WaypointsMotion,
    ZigZagMotion,
)

__all__ = [
    "TELEOP_TIMEOUT_S",
    "CircleModel",
    "MotionModel",
    "RandomWalkModel",
    "SmoothModel",
    "StaticModel",
    "TeleopModel",
    "WaypointsModel",
    "ZigZagModel",
    "make_motion",
]

TELEOP_TIMEOUT_S = 0.5
"""A teleop command older than this (world time, s) stops the object."""

_ZERO = np.zeros(3)


class MotionModel(Protocol):
    def advance(
        self, position: np.ndarray, time_s: float, dt_s: float
    ) -> tuple[np.ndarray, np.ndarray]:
        """The position after ``dt_s`` seconds (ENU m) and the velocity over the step (m/s)."""
        ...


class StaticModel:
    """Does not move."""

    def advance(
        self, position: np.ndarray, time_s: float, dt_s: float
    ) -> tuple[np.ndarray, np.ndarray]:
        return position.copy(), _ZERO.copy()


class WaypointsModel:
    """Constant speed along straight segments through the waypoints (pingpong, loop or once)."""

    def __init__(self, spec: WaypointsMotion) -> None:
        self.points = [np.array(p, dtype=float) for p in spec.points]
        self.speed = spec.speed_m_s
        self.mode = spec.mode
        self.index = 0  # the waypoint we are heading for
        self.step_dir = 1  # +1 forward through the list, -1 backward (pingpong)
        self.done = False

    def _next_index(self) -> None:
        n = len(self.points)
        if self.mode == "loop":
            self.index = (self.index + 1) % n
        elif self.mode == "once":
            if self.index == n - 1:
                self.done = True
            else:
                self.index += 1
        else:  # pingpong
            if n == 1:
                self.done = True
                return
            if not 0 <= self.index + self.step_dir < n:
                self.step_dir = -self.step_dir
            self.index += self.step_dir

    def advance(
        self, position: np.ndarray, time_s: float, dt_s: float
    ) -> tuple[np.ndarray, np.ndarray]:
        pos = position.astype(float).copy()
        budget = self.speed * dt_s
        for _ in range(4 * len(self.points) + 4):  # bounded: a few segments per step at most
            if self.done or budget <= 0:
                break
            offset = self.points[self.index] - pos
            dist = float(np.linalg.norm(offset))
            if dist > budget:
                pos += offset / dist * budget
                budget = 0.0
            else:
                pos = self.points[self.index].copy()
                budget -= dist
                self._next_index()
        velocity = (pos - position) / dt_s if dt_s > 0 else _ZERO.copy()
        return pos, velocity


class CircleModel:
    """A horizontal circle at constant speed, starting at the angle of the start position."""

    def __init__(self, spec: CircleMotion, start: np.ndarray) -> None:
        self.center = np.array(spec.center, dtype=float)
        self.radius = spec.radius_m
        self.omega = spec.speed_m_s / spec.radius_m * (-1.0 if spec.clockwise else 1.0)
        rel = start[:2] - self.center[:2]
        self.angle = math.atan2(rel[1], rel[0]) if np.hypot(*rel) > 1e-9 else 0.0

    def _point(self, angle: float) -> np.ndarray:
        return self.center + np.array(
            [self.radius * math.cos(angle), self.radius * math.sin(angle), 0.0]
        )

    def advance(
        self, position: np.ndarray, time_s: float, dt_s: float
    ) -> tuple[np.ndarray, np.ndarray]:
        self.angle = math.remainder(self.angle + self.omega * dt_s, math.tau)
        speed = self.omega * self.radius
        velocity = np.array([-math.sin(self.angle) * speed, math.cos(self.angle) * speed, 0.0])
        return self._point(self.angle), velocity


class ZigZagModel:
    """The paper's abrupt beacon: vertical legs between two heights at random speeds, with the
    horizontal direction flipping at every turn (and at the lateral limits)."""

    def __init__(self, spec: ZigZagMotion, start: np.ndarray, rng: np.random.Generator) -> None:
        self.spec = spec
        self.rng = rng
        d = np.array([spec.direction[0], spec.direction[1], 0.0], dtype=float)
        self.axis = d / np.linalg.norm(d)
        self.origin = start.astype(float).copy()
        self.vertical_sign = 1.0 if start[2] < spec.z_max_m else -1.0
        self.horizontal_sign = 1.0
        self.vertical_speed = self._draw_speed()

    def _draw_speed(self) -> float:
        s = self.spec
        return float(self.rng.uniform(s.vertical_speed_min_m_s, s.vertical_speed_max_m_s))

    def _turn(self, vertical_sign: float) -> None:
        self.vertical_sign = vertical_sign
        self.horizontal_sign = -self.horizontal_sign
        self.vertical_speed = self._draw_speed()

    def advance(
        self, position: np.ndarray, time_s: float, dt_s: float
    ) -> tuple[np.ndarray, np.ndarray]:
        s = self.spec
        velocity = self.axis * (self.horizontal_sign * s.horizontal_speed_m_s)
        velocity[2] = self.vertical_sign * self.vertical_speed
        pos = position.astype(float) + velocity * dt_s
        if pos[2] >= s.z_max_m and self.vertical_sign > 0:
            pos[2] = s.z_max_m
            self._turn(-1.0)
        elif pos[2] <= s.z_min_m and self.vertical_sign < 0:
            pos[2] = s.z_min_m
            self._turn(1.0)
        lateral = float(np.dot(pos - self.origin, self.axis))
        if abs(lateral) >= s.half_width_m:  # at the side limit: clamp and head back inwards
            pos -= self.axis * (lateral - math.copysign(s.half_width_m, lateral))
            self.horizontal_sign = -math.copysign(1.0, lateral)
        return pos, velocity


class SmoothModel:
    """Sinusoids about the start position, one per ENU axis, phases drawn from the seed."""

    def __init__(self, spec: SmoothMotion, start: np.ndarray, rng: np.random.Generator) -> None:
        self.amplitude = np.array(spec.amplitude_m, dtype=float)
        self.omega = 2.0 * math.pi / np.array(spec.period_s, dtype=float)
        self.phase = rng.uniform(0.0, 2.0 * math.pi, size=3)
        # offset so that the object is exactly at its start position at t = 0
        self.center = start.astype(float) - self.amplitude * np.sin(self.phase)
        self.elapsed = 0.0

    def advance(
        self, position: np.ndarray, time_s: float, dt_s: float
    ) -> tuple[np.ndarray, np.ndarray]:
        self.elapsed += dt_s
        arg = self.omega * self.elapsed + self.phase
        pos = self.center + self.amplitude * np.sin(arg)
        velocity = self.amplitude * self.omega * np.cos(arg)
        return pos, velocity


class RandomWalkModel:
    """Random straight legs inside a disc at random speeds, with optional pauses."""

    def __init__(self, spec: RandomWalkMotion, rng: np.random.Generator) -> None:
        self.spec = spec
        self.rng = rng
        self.center = np.array(spec.center, dtype=float)
        self.goal: np.ndarray | None = None
        self.speed = 0.0
        self.pause_left = 0.0

    def _pick_goal(self, pos: np.ndarray) -> None:
        s = self.spec
        goal = self.center.copy()
        for _ in range(20):  # bounded retries for a leg at least min_leg_m long
            r = s.radius_m * math.sqrt(self.rng.uniform())
            a = self.rng.uniform(0.0, 2.0 * math.pi)
            goal = self.center + np.array([r * math.cos(a), r * math.sin(a)])
            if np.linalg.norm(goal - pos[:2]) >= s.min_leg_m:
                break
        self.goal = goal
        self.speed = float(self.rng.uniform(s.speed_min_m_s, s.speed_max_m_s))

    def advance(
        self, position: np.ndarray, time_s: float, dt_s: float
    ) -> tuple[np.ndarray, np.ndarray]:
        pos = position.astype(float).copy()
        left = dt_s
        for _ in range(8):  # bounded: at most a few legs or pauses end within one step
            if left <= 1e-12:
                break
            if self.pause_left > 0:
                used = min(self.pause_left, left)
                self.pause_left -= used
                left -= used
                continue
            if self.goal is None:
                self._pick_goal(pos)
            assert self.goal is not None
            offset = self.goal - pos[:2]
            dist = float(np.linalg.norm(offset))
            reach = self.speed * left
            if dist > reach:
                pos[:2] += offset / dist * reach
                left = 0.0
            else:
                pos[:2] = self.goal
                left -= dist / self.speed
                self.goal = None
                s = self.spec
                self.pause_left = float(self.rng.uniform(s.pause_min_s, s.pause_max_s))
        velocity = (pos - position) / dt_s if dt_s > 0 else _ZERO.copy()
        return pos, velocity


class TeleopModel:
    """Follows the last velocity command (ENU m/s, yaw rate rad/s) until it is older than
    :data:`TELEOP_TIMEOUT_S` of world time; then stands still."""

    def __init__(self) -> None:
        self.linear = np.zeros(3)
        self.yaw_rate = 0.0
        self.stamp_s = -math.inf

    def command(self, linear_enu: np.ndarray, yaw_rate: float, now_s: float) -> None:
        """Store a command received at world time ``now_s`` (s)."""
        linear = np.asarray(linear_enu, dtype=float).reshape(3)
        if not (np.all(np.isfinite(linear)) and math.isfinite(yaw_rate)):
            raise ValueError("cmd_vel must be finite")
        if not math.isfinite(now_s):
            raise ValueError("now_s must be finite")
        self.linear = linear.copy()
        self.yaw_rate = float(yaw_rate)
        self.stamp_s = float(now_s)

    def fresh(self, time_s: float) -> bool:
        """Whether the last command is still in force at world time ``time_s``."""
        return time_s - self.stamp_s <= TELEOP_TIMEOUT_S

    def advance(
        self, position: np.ndarray, time_s: float, dt_s: float
    ) -> tuple[np.ndarray, np.ndarray]:
        if not self.fresh(time_s):
            return position.copy(), _ZERO.copy()
        return position + self.linear * dt_s, self.linear.copy()


def make_motion(spec: Motion, start: np.ndarray, rng: np.random.Generator) -> MotionModel:
    """The motion model for a scenario's motion spec, starting at ``start`` (ENU m)."""
    if isinstance(spec, StaticMotion):
        return StaticModel()
    if isinstance(spec, WaypointsMotion):
        return WaypointsModel(spec)
    if isinstance(spec, CircleMotion):
        return CircleModel(spec, start)
    if isinstance(spec, ZigZagMotion):
        return ZigZagModel(spec, start, rng)
    if isinstance(spec, SmoothMotion):
        return SmoothModel(spec, start, rng)
    if isinstance(spec, RandomWalkMotion):
        return RandomWalkModel(spec, rng)
    if isinstance(spec, TeleopMotion):
        return TeleopModel()
    raise TypeError(f"unknown motion spec {type(spec).__name__}")
