"""PX4-style multicopter position and velocity control: a target -> attitude and thrust.

Cascaded like PX4's ``PositionControl``: position error -> velocity setpoint (P, limited),
velocity error -> acceleration (PI, with feed-forward), acceleration -> tilt and collective
thrust (tilt limited to MPC_TILTMAX_AIR, vertical thrust first). Heading: a yaw target is
tracked with a P gain, else a yaw rate is followed. Everything in local ENU; ``NaN`` in a
target field means "not controlled", as in PX4's trajectory setpoints.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TypedDict

from dronewrapper_sim.dynamics import GRAVITY, ControlInput, QuadState
from dronewrapper_sim.frames import wrap_pi
from dronewrapper_sim.px4.params import ParamStore

NAN = float("nan")


class Limits(TypedDict):
    """A mode's speed limits, as :class:`Target` keywords (m/s, rad/s)."""

    max_xy: float
    max_up: float
    max_down: float
    max_yaw_rate: float


def _finite(a: float, b: float) -> bool:
    return math.isfinite(a) and math.isfinite(b)


@dataclass(frozen=True)
class Target:
    """What the vehicle should do now, local ENU (m, m/s, m/s^2, rad, rad/s); NaN = free.

    Attributes:
        position, velocity, acceleration: per-axis targets; a finite position wins over a
            velocity on its axis (the velocity is then a feed-forward).
        yaw: heading to hold (ENU, rad), else ``yaw_rate`` (rad/s, CCW), else keep turning 0.
        max_xy, max_up, max_down: speed limits (m/s) for this mode.
        max_yaw_rate: yaw rate limit (rad/s) for this mode.
        idle: motors at idle on the ground (spool-up, landed, disarmed in the air = no thrust).
    """

    position: tuple[float, float, float] = (NAN, NAN, NAN)
    velocity: tuple[float, float, float] = (NAN, NAN, NAN)
    acceleration: tuple[float, float, float] = (NAN, NAN, NAN)
    yaw: float = NAN
    yaw_rate: float = NAN
    max_xy: float = 12.0
    max_up: float = 3.0
    max_down: float = 1.5
    max_yaw_rate: float = math.radians(200.0)
    idle: bool = False

    def is_valid(self) -> bool:
        """Every axis has a finite position, velocity or acceleration (x and y together)."""
        p, v, a = self.position, self.velocity, self.acceleration
        xy = _finite(p[0], p[1]) or _finite(v[0], v[1]) or _finite(a[0], a[1])
        return xy and (math.isfinite(p[2]) or math.isfinite(v[2]) or math.isfinite(a[2]))


@dataclass(frozen=True)
class Gains:
    """Controller gains (PX4 parameter names in brackets)."""

    xy_p: float = 0.95  # MPC_XY_P
    z_p: float = 1.0  # MPC_Z_P
    vel_xy_p: float = 1.8  # MPC_XY_VEL_P_ACC
    vel_xy_i: float = 0.4  # MPC_XY_VEL_I_ACC
    vel_z_p: float = 4.0  # MPC_Z_VEL_P_ACC
    vel_z_i: float = 2.0  # MPC_Z_VEL_I_ACC
    yaw_p: float = 2.8  # MC_YAW_P
    max_tilt_rad: float = math.radians(45.0)  # MPC_TILTMAX_AIR
    hover_thrust: float = GRAVITY  # thrust acceleration that holds altitude (m/s^2)
    max_thrust: float = 2.0 * GRAVITY  # thrust acceleration at full throttle (m/s^2)

    @classmethod
    def from_params(cls, params: ParamStore, hover: float, max_thrust: float) -> Gains:
        """The gains PX4 parameters set, with the vehicle's hover and full thrust (m/s^2)."""
        return cls(
            xy_p=params["MPC_XY_P"],
            z_p=params["MPC_Z_P"],
            vel_xy_p=params["MPC_XY_VEL_P_ACC"],
            vel_xy_i=params["MPC_XY_VEL_I_ACC"],
            vel_z_p=params["MPC_Z_VEL_P_ACC"],
            vel_z_i=params["MPC_Z_VEL_I_ACC"],
            yaw_p=params["MPC_YAW_P"],
            max_tilt_rad=math.radians(params["MPC_TILTMAX_AIR"]),
            hover_thrust=hover,
            max_thrust=max_thrust,
        )


def _limit_norm(x: float, y: float, limit: float) -> tuple[float, float]:
    norm = math.hypot(x, y)
    if norm > limit > 0:
        return x * limit / norm, y * limit / norm
    return x, y


class PositionController:
    """The controller with its integrators (reset when the vehicle is idle on the ground)."""

    def __init__(self, gains: Gains | None = None) -> None:
        self.gains = gains or Gains()
        self.integral = [0.0, 0.0, 0.0]
        self.velocity_setpoint = (0.0, 0.0, 0.0)
        self.valid = True

    def reset(self) -> None:
        """Forget the integrators (on the ground, at arming)."""
        self.integral = [0.0, 0.0, 0.0]

    def velocity_sp(self, target: Target, s: QuadState) -> tuple[float, float, float]:
        """The velocity setpoint (ENU m/s) for ``target`` from state ``s``, limited."""
        g = self.gains
        px, py, pz = target.position
        vx_ff, vy_ff, vz_ff = (v if math.isfinite(v) else 0.0 for v in target.velocity)
        if _finite(px, py):
            vx = g.xy_p * (px - s.x) + vx_ff
            vy = g.xy_p * (py - s.y) + vy_ff
        elif _finite(*target.velocity[:2]):
            vx, vy = target.velocity[0], target.velocity[1]
        elif _finite(*target.acceleration[:2]):
            vx, vy = s.vx, s.vy  # acceleration control: no velocity error
        else:
            vx = vy = 0.0  # invalid: hold
        vx, vy = _limit_norm(vx, vy, target.max_xy)
        if math.isfinite(pz):
            vz = g.z_p * (pz - s.z) + vz_ff
        elif math.isfinite(target.velocity[2]):
            vz = target.velocity[2]
        elif math.isfinite(target.acceleration[2]):
            vz = s.vz
        else:
            vz = 0.0
        vz = min(max(vz, -target.max_down), target.max_up)
        return vx, vy, vz

    def update(self, target: Target, s: QuadState, dt: float) -> ControlInput:
        """Attitude, yaw rate and thrust commands for ``target`` (one control period ``dt``)."""
        g = self.gains
        self.valid = target.is_valid()
        if target.idle:
            self.reset()
            self.velocity_setpoint = (0.0, 0.0, 0.0)
            return ControlInput(thrust=0.0)
        vsp = self.velocity_sp(target, s)
        self.velocity_setpoint = vsp
        ff = [a if math.isfinite(a) else 0.0 for a in target.acceleration]
        err = (vsp[0] - s.vx, vsp[1] - s.vy, vsp[2] - s.vz)
        acc = [
            g.vel_xy_p * err[0] + self.integral[0] + ff[0],
            g.vel_xy_p * err[1] + self.integral[1] + ff[1],
            g.vel_z_p * err[2] + self.integral[2] + ff[2],
        ]
        # vertical first: thrust along z within [10 % , max] of the hover reference
        thrust_z = min(max(g.hover_thrust + acc[2], 0.1 * g.hover_thrust), g.max_thrust)
        max_h = min(
            thrust_z * math.tan(g.max_tilt_rad),
            math.sqrt(max(g.max_thrust**2 - thrust_z**2, 0.0)),
        )
        ax, ay = _limit_norm(acc[0], acc[1], max_h)
        saturated_xy = math.hypot(acc[0], acc[1]) > max_h
        # integrate (anti-windup: not while saturated, and bounded)
        if not saturated_xy:
            self.integral[0] = _clip(self.integral[0] + g.vel_xy_i * err[0] * dt, GRAVITY)
            self.integral[1] = _clip(self.integral[1] + g.vel_xy_i * err[1] * dt, GRAVITY)
        if g.hover_thrust + acc[2] == thrust_z:
            self.integral[2] = _clip(self.integral[2] + g.vel_z_i * err[2] * dt, 5.0)

        # tilt in the heading frame: forward acceleration pitches nose down (FLU pitch > 0)
        c, sn = math.cos(s.yaw), math.sin(s.yaw)
        a_fwd = c * ax + sn * ay
        a_left = -sn * ax + c * ay
        pitch = math.atan2(a_fwd, thrust_z)
        roll = math.atan2(-a_left, math.hypot(a_fwd, thrust_z))
        thrust = math.sqrt(thrust_z**2 + ax * ax + ay * ay)

        if math.isfinite(target.yaw):
            yaw_rate = g.yaw_p * wrap_pi(target.yaw - s.yaw)
            if math.isfinite(target.yaw_rate):
                yaw_rate += target.yaw_rate
        elif math.isfinite(target.yaw_rate):
            yaw_rate = target.yaw_rate
        else:
            yaw_rate = 0.0
        yaw_rate = min(max(yaw_rate, -target.max_yaw_rate), target.max_yaw_rate)
        return ControlInput(roll=roll, pitch=pitch, yaw_rate=yaw_rate, thrust=thrust)


def _clip(value: float, limit: float) -> float:
    return min(max(value, -limit), limit)
