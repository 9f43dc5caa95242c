"""The DJI Tello airframe and its flight envelope, as the simulated Tello flies them.

Figures: DJI's specifications (87 g with propellers and guards, 1.1 Ah 3.8 V battery,
13 min flight, 8 m/s top speed, 82.6 deg diagonal field of view, 960x720 30 fps video) and
the Tello SDK 2.0 user guide (command ranges); the rest is chosen so that the simulated Tello
responds like the real one in normal (not sport) mode.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from dronewrapper_sim.dynamics import GRAVITY, QuadParams
from dronewrapper_sim.px4.flight_control import Gains

TELLO_QUAD = QuadParams(
    max_thrust_accel=2.2 * GRAVITY,
    drag_xy=0.5,
    drag_z=0.5,
    attitude_tau_s=0.06,
    thrust_tau_s=0.03,
    yaw_rate_tau_s=0.08,
    max_tilt_rad=math.radians(35.0),
    max_yaw_rate=math.radians(150.0),
)
"""The Tello's rigid-body constants for :func:`dronewrapper_sim.dynamics.step`."""

TELLO_GAINS = Gains(
    xy_p=1.2,
    z_p=1.5,
    vel_xy_p=2.5,
    vel_xy_i=0.5,
    vel_z_p=5.0,
    vel_z_i=2.0,
    yaw_p=3.0,
    max_tilt_rad=math.radians(25.0),
    max_thrust=2.2 * GRAVITY,
)
"""The Tello's position/velocity controller (normal mode tilt limit 25 deg)."""


@dataclass(frozen=True)
class TelloEnvelope:
    """Speeds, heights and timings of the simulated Tello (SI units unless named otherwise).

    Attributes:
        rc_max_xy: horizontal speed at rc 100, m/s (normal mode).
        rc_max_z: vertical speed at rc 100, m/s.
        rc_max_yaw_rate: yaw rate at rc 100, rad/s.
        rotate_rate: yaw rate of ``cw``/``ccw``, rad/s.
        takeoff_height: hover height after ``takeoff`` above the ground, m.
        takeoff_speed: climb speed during take-off, m/s.
        spool_up_s: motors spinning up before lift-off, s.
        land_speed: descent speed of ``land``, m/s.
        default_speed: speed of the moves until ``speed`` changes it, m/s.
        arrive_m: a manoeuvre has arrived within this distance, m.
        arrive_yaw: a rotation has arrived within this angle, rad.
        settle_speed: and once slower than this, m/s.
        flip_s: duration of a flip, s.
        auto_land_s: lands after this long without any command, s.
        low_battery_takeoff: take-off refused at or below this charge, %.
        low_battery_land: lands by itself at or below this charge, %.
        flip_battery: flips refused below this charge, %.
        capacity_mah: battery capacity, mAh.
        idle_current_a: current drawn powered on, motors off, A.
        hover_current_a: extra current at hover thrust, A (13 min from a full pack).
    """

    rc_max_xy: float = 1.0
    rc_max_z: float = 1.0
    rc_max_yaw_rate: float = math.radians(100.0)
    rotate_rate: float = math.radians(90.0)
    takeoff_height: float = 0.9
    takeoff_speed: float = 0.6
    spool_up_s: float = 1.0
    land_speed: float = 0.5
    default_speed: float = 1.0
    arrive_m: float = 0.05
    arrive_yaw: float = math.radians(2.0)
    settle_speed: float = 0.1
    flip_s: float = 1.0
    auto_land_s: float = 15.0
    low_battery_takeoff: int = 10
    low_battery_land: int = 5
    flip_battery: int = 50
    capacity_mah: float = 1100.0
    idle_current_a: float = 0.3
    hover_current_a: float = 4.7


TELLO = TelloEnvelope()

CAMERA_WIDTH = 960
CAMERA_HEIGHT = 720
CAMERA_RATE_HZ = 30.0
CAMERA_DIAGONAL_FOV_DEG = 82.6


def camera_hfov_rad(width: int = CAMERA_WIDTH, height: int = CAMERA_HEIGHT) -> float:
    """Horizontal field of view (rad) of the Tello's camera from its diagonal one (82.6 deg)."""
    half_diag = math.tan(math.radians(CAMERA_DIAGONAL_FOV_DEG) / 2.0)
    return 2.0 * math.atan(half_diag * width / math.hypot(width, height))
