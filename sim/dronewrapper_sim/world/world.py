"""The simulated world: objects (a red beacon, people) moving by their motion models.

Pure and deterministic: no clock (time advances by :meth:`World.step`), every random choice from
the scenario's seed. Positions ENU m (a person's base point on the ground, a beacon's centre),
velocities ENU m/s, yaw rad CCW from east.
"""

from __future__ import annotations

import math
import zlib
from dataclasses import dataclass, field

import numpy as np

from dronewrapper_sim.world.looks import PersonLook, random_look
from dronewrapper_sim.world.motion import MotionModel, TeleopModel, make_motion
from dronewrapper_sim.world.scenario import ObjectSpec, Scenario

__all__ = ["MAX_SUBSTEP_S", "World", "WorldObject"]

MAX_SUBSTEP_S = 0.05
"""Longer steps are split into sub-steps of at most this (s), so turns happen on time."""

PERSON_TURN_RATE = 5.0  # rad/s: how fast a walking person turns to face where they walk
PERSON_HEIGHT_RANGE_M = (1.60, 1.90)


@dataclass
class WorldObject:
    """One object of the world and its state.

    Attributes:
        name: unique name (the followed one is ``target``).
        kind: ``beacon`` or ``person``.
        position: ENU m (person: base point on the ground, z = 0; beacon: centre).
        yaw: heading, rad (ENU, CCW from east).
        velocity: ENU m/s over the last step.
        motion: the motion model moving it.
        radius_m: beacon radius, m.
        height_m: person height, m (beacon: its diameter).
        color_bgr: beacon colour.
        look: a person's clothing (None for a beacon).
        sprite: sprite file chosen for a person (used when the renderer has sprites).
        sprite_index: a seeded random integer for choosing a sprite when ``sprite`` is None.
        walk_phase: gait phase, rad (one full cycle = two steps).
        gait: 0 (standing) .. 1 (full stride), smoothed.
        yaw_rate: rad/s over the last step.
    """

    name: str
    kind: str
    position: np.ndarray
    yaw: float
    velocity: np.ndarray
    motion: MotionModel
    radius_m: float = 0.3
    height_m: float = 1.75
    color_bgr: tuple[int, int, int] = (20, 20, 215)
    look: PersonLook | None = None
    sprite: str | None = None
    sprite_index: int = 0
    walk_phase: float = 0.0
    gait: float = 0.0
    yaw_rate: float = 0.0
    teleop: TeleopModel | None = field(default=None, repr=False)

    @property
    def top_enu(self) -> np.ndarray:
        """The object's highest point (ENU m)."""
        if self.kind == "person":
            return self.position + np.array([0.0, 0.0, self.height_m])
        return self.position + np.array([0.0, 0.0, self.radius_m])

    @property
    def center_enu(self) -> np.ndarray:
        """The object's centre (ENU m): a beacon's centre, a person's mid-height."""
        if self.kind == "person":
            return self.position + np.array([0.0, 0.0, self.height_m / 2.0])
        return self.position.copy()


def _rng(seed: int, name: str, stream: int) -> np.random.Generator:
    """A generator for one object and purpose, stable when other objects are added/removed."""
    return np.random.default_rng([seed & 0xFFFFFFFF, zlib.crc32(name.encode()), stream])


def _make_object(spec: ObjectSpec, seed: int) -> WorldObject:
    look_rng = _rng(seed, spec.name, 0)
    start = np.array(spec.position, dtype=float)
    if spec.kind == "person":
        start[2] = 0.0
        height = spec.height_m or float(look_rng.uniform(*PERSON_HEIGHT_RANGE_M))
        look = random_look(look_rng, spec.look)
    else:
        start[2] = max(start[2], spec.radius_m)
        height = 2.0 * spec.radius_m
        look = None
    return WorldObject(
        name=spec.name,
        kind=spec.kind,
        position=start,
        yaw=float(spec.yaw),
        velocity=np.zeros(3),
        motion=make_motion(spec.motion, start, _rng(seed, spec.name, 1)),
        radius_m=spec.radius_m,
        height_m=height,
        color_bgr=spec.color_bgr,
        look=look,
        sprite=spec.sprite,
        sprite_index=int(look_rng.integers(1 << 30)),
        walk_phase=float(look_rng.uniform(0.0, 2.0 * math.pi)),
    )


class World:
    """All objects of a scenario and their motion.

    Args:
        scenario: the scenario to build.
        seed: overrides ``scenario.seed`` when given.
    """

    def __init__(self, scenario: Scenario, seed: int | None = None) -> None:
        self.load(scenario, seed)

    def load(self, scenario: Scenario, seed: int | None = None) -> None:
        """Become ``scenario``'s world at time 0: its objects from their scripted start. In
        place, so every holder of this world (renderer, publishers) sees the new one."""
        self.scenario = scenario
        self.seed = scenario.seed if seed is None else int(seed)
        self.time_s = 0.0
        self.objects: list[WorldObject] = [_make_object(s, self.seed) for s in scenario.objects]
        self._by_name = {obj.name: obj for obj in self.objects}

    def object(self, name: str) -> WorldObject:
        """The object called ``name``; KeyError naming the known objects otherwise."""
        try:
            return self._by_name[name]
        except KeyError:
            known = ", ".join(self._by_name) or "none"
            raise KeyError(f"no object {name!r} in the world (objects: {known})") from None

    def set_cmd_vel(self, name: str, linear_enu: np.ndarray, yaw_rate: float, now_s: float) -> None:
        """Teleoperate ``name``: velocity ENU m/s and yaw rate rad/s, received at world time
        ``now_s`` (s, on the :attr:`time_s` clock). From the first command on, the object
        follows commands only (its scripted motion ends); a command older than 0.5 s stops it.
        A person ignores the vertical component. Raises KeyError or ValueError (non-finite)."""
        obj = self.object(name)
        teleop = obj.teleop or TeleopModel()
        teleop.command(linear_enu, yaw_rate, now_s)
        obj.teleop = teleop
        obj.motion = teleop

    def step(self, dt_s: float) -> None:
        """Advance the world by ``dt_s`` seconds (split into sub-steps of <= 50 ms)."""
        if not (math.isfinite(dt_s) and dt_s >= 0.0):
            raise ValueError(f"dt_s must be finite and >= 0, got {dt_s}")
        n = max(1, math.ceil(dt_s / MAX_SUBSTEP_S - 1e-9))
        sub = dt_s / n
        for _ in range(n):
            if sub > 0:
                for obj in self.objects:
                    self._advance(obj, sub)
            self.time_s += sub

    def _advance(self, obj: WorldObject, dt: float) -> None:
        new_pos, velocity = obj.motion.advance(obj.position, self.time_s, dt)
        teleop = obj.teleop if obj.motion is obj.teleop else None
        yaw_rate = teleop.yaw_rate if teleop is not None and teleop.fresh(self.time_s) else 0.0
        if obj.kind == "person":
            new_pos[2] = 0.0
            velocity = velocity.copy()
            velocity[2] = 0.0
        else:
            new_pos[2] = max(new_pos[2], obj.radius_m)  # ground contact
        obj.position = new_pos
        obj.velocity = velocity
        old_yaw = obj.yaw
        speed = float(math.hypot(velocity[0], velocity[1]))
        if yaw_rate != 0.0:
            obj.yaw = math.remainder(obj.yaw + yaw_rate * dt, math.tau)
        elif obj.kind == "person" and speed > 0.05:
            heading = math.atan2(velocity[1], velocity[0])
            error = math.remainder(heading - obj.yaw, math.tau)
            turn = max(-PERSON_TURN_RATE * dt, min(PERSON_TURN_RATE * dt, error))
            obj.yaw = math.remainder(obj.yaw + turn, math.tau)
        obj.yaw_rate = math.remainder(obj.yaw - old_yaw, math.tau) / dt
        if obj.kind == "person":
            step_length = 0.3 + 0.25 * speed  # m per step
            obj.walk_phase = (obj.walk_phase + math.pi * speed / step_length * dt) % math.tau
            target_gait = min(1.0, speed / 1.2)
            obj.gait += max(-3.0 * dt, min(3.0 * dt, target_gait - obj.gait))
