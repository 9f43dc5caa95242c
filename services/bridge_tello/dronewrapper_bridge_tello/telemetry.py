"""Tello state strings -> MAVROS-shaped messages, with a dead-reckoned position.

Pure: every method takes the wall-clock stamp (float s since the epoch) and a monotonic time
(s), and nothing here does I/O.

* Orientation: the Tello's degrees -> an ENU/FLU quaternion (see :mod:`.frames`).
* Velocities: ``vgx, vgy, vgz`` (dm/s, ``velocity_unit`` m each) in the frame named by
  ``velocity_frame``: ``reference`` (x along the Tello's reference heading, y to its right, z
  down: what the real drone sends) or ``body_frd`` (forward, right, down of the current
  heading). Local velocity is ENU, body velocity FLU.
* The local frame: x along ``reference_yaw`` (rad ENU; 0: the Tello's power-on heading is +x).
* Position: a Tello has no position sensor. x, y are **dead-reckoned** by integrating the
  ENU velocity between state strings, reset to 0 on each take-off, so they drift; z is the
  height ``h`` (cm above the take-off point) or ``tof`` (cm to the ground, minus its reading on
  the ground). The pose's ``header.frame_id`` is ``odom`` (ROS's name for a continuous but
  drifting frame) instead of ``map``.
* Landed state: from the bridge's own commands (take-off / land in progress) and from motion
  (the motor time counter advancing, the height), see :class:`LandedTracker`.
* Battery: percentage 0..1, voltage unknown (NaN): the Tello does not send it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from dronewrapper.msgs.geometry import PoseStamped, TwistStamped, Vector3
from dronewrapper.msgs.mavros import (
    LANDED_STATE_IN_AIR,
    LANDED_STATE_LANDING,
    LANDED_STATE_ON_GROUND,
    LANDED_STATE_TAKEOFF,
)
from dronewrapper.msgs.sensor import BatteryState
from dronewrapper.msgs.std import Header
from dronewrapper_bridge_base.odometry import Headers, odometry
from dronewrapper_bridge_tello.frames import Quat, Vec3, attitude_enu, rotate
from dronewrapper_bridge_tello.state import TelloState

FRAME_ODOM = "odom"
VELOCITY_FRAMES = ("reference", "body_frd")
HEIGHT_SOURCES = ("h", "tof")
MAX_INTEGRATION_STEP = 0.5  # s: a longer gap between state strings is not integrated over


def velocity_enu(
    state: TelloState, q: Quat, frame: str, unit: float, reference_yaw: float = 0.0
) -> Vec3:
    """The state's velocity as local ENU m/s (``q``: the attitude, ``unit``: m per vg unit,
    ``reference_yaw``: ENU yaw of the Tello's reference heading, rad)."""
    a, b, c = state.vgx * unit, state.vgy * unit, state.vgz * unit
    if frame == "reference":  # forward, right, down of the reference heading
        cos, sin = math.cos(reference_yaw), math.sin(reference_yaw)
        return (cos * a + sin * b, sin * a - cos * b, -c)
    return rotate(q, (a, -b, -c))  # body FRD -> FLU, then into ENU


@dataclass
class LandedTracker:
    """The landed state, from the bridge's commands and the drone's motion.

    * take-off sent -> TAKEOFF, its ``ok`` -> IN_AIR (a refusal: back to what motion says);
    * land sent -> LANDING, its ``ok`` -> ON_GROUND;
    * otherwise from motion: the motor time counter advances once a second while the motors run;
      in the air, a height at or below ``ground_cm`` with no motor tick for ``motors_off_s``
      means landed (auto-land, emergency, a second client's ``land``); on the ground, a height
      above ``airborne_cm`` with the motors running means flying (a second client's take-off).
    """

    ground_cm: float = 10.0
    airborne_cm: float = 20.0
    motors_off_s: float = 2.5
    state: int = LANDED_STATE_ON_GROUND
    _motor_time: float = -1.0
    _motor_tick_at: float = -math.inf

    @property
    def flying(self) -> bool:
        """True unless on the ground (take-off, in the air, landing)."""
        return self.state != LANDED_STATE_ON_GROUND

    def on_takeoff_sent(self) -> None:
        self.state = LANDED_STATE_TAKEOFF

    def on_takeoff_done(self, ok: bool) -> None:
        self.state = LANDED_STATE_IN_AIR if ok else LANDED_STATE_ON_GROUND

    def on_land_sent(self) -> None:
        if self.state != LANDED_STATE_ON_GROUND:
            self.state = LANDED_STATE_LANDING

    def on_land_done(self, ok: bool) -> None:
        if ok:
            self.state = LANDED_STATE_ON_GROUND
        elif self.state == LANDED_STATE_LANDING:
            self.state = LANDED_STATE_IN_AIR

    def on_emergency(self) -> None:
        self.state = LANDED_STATE_LANDING  # falling; ON_GROUND once motion says so

    def on_state(self, height_cm: float, motor_time_s: float, now: float) -> None:
        """Feed one state string's height (cm) and motor time (s) at monotonic ``now``."""
        if motor_time_s != self._motor_time:
            if self._motor_time >= 0 and motor_time_s > self._motor_time:
                self._motor_tick_at = now
            self._motor_time = motor_time_s
        motors_running = now - self._motor_tick_at <= self.motors_off_s
        if self.state in (LANDED_STATE_IN_AIR, LANDED_STATE_LANDING):
            if height_cm <= self.ground_cm and not motors_running:
                self.state = LANDED_STATE_ON_GROUND
        elif (
            self.state == LANDED_STATE_ON_GROUND and height_cm > self.airborne_cm and motors_running
        ):
            self.state = LANDED_STATE_IN_AIR


@dataclass
class Telemetry:
    """The latest Tello state as messages, and the dead-reckoned position.

    Attributes:
        attitude: body FLU in local ENU (x, y, z, w).
        position_enu: estimated position (m, ENU; x, y dead-reckoned), None before a state.
        velocity: latest ENU velocity (m/s).
        battery: latest percentage 0..1 (NaN before a state).
    """

    velocity_frame: str = "reference"
    reference_yaw: float = 0.0  # rad, ENU yaw of the Tello's yaw 0
    velocity_unit: float = 0.1  # m/s per vg* unit (dm/s)
    height_source: str = "h"
    tof_ground_cm: float = 10.0
    attitude: Quat = (0.0, 0.0, 0.0, 1.0)
    position_enu: Vec3 | None = None
    velocity: Vec3 = (0.0, 0.0, 0.0)
    battery: float = math.nan
    landed: LandedTracker = field(default_factory=LandedTracker)
    _xy: tuple[float, float] = (0.0, 0.0)
    _last_at: float | None = None
    _yaw_rate: float = 0.0
    _last_yaw: float | None = None
    headers: Headers = field(default_factory=Headers)

    def __post_init__(self) -> None:
        if self.velocity_frame not in VELOCITY_FRAMES:
            raise ValueError(f"velocity_frame must be one of {VELOCITY_FRAMES}")
        if self.height_source not in HEIGHT_SOURCES:
            raise ValueError(f"height_source must be one of {HEIGHT_SOURCES}")

    @property
    def yaw_enu(self) -> float:
        """Current heading (rad, ENU, CCW from east)."""
        x, y, z, w = self.attitude
        return math.atan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z))

    def reset_position(self) -> None:
        """Take-off: the local frame's origin is here (x, y = 0)."""
        self._xy = (0.0, 0.0)
        if self.position_enu is not None:
            self.position_enu = (0.0, 0.0, self.position_enu[2])

    def _height(self, state: TelloState) -> float:
        if self.height_source == "tof":
            return max(0.0, state.tof_cm - self.tof_ground_cm) / 100.0
        return state.h_cm / 100.0

    def on_state(self, state: TelloState, now: float) -> None:
        """Feed one parsed state string received at monotonic ``now``."""
        self.attitude = attitude_enu(
            state.roll_deg, state.pitch_deg, state.yaw_deg, self.reference_yaw
        )
        v = velocity_enu(
            state, self.attitude, self.velocity_frame, self.velocity_unit, self.reference_yaw
        )
        yaw = self.yaw_enu
        if self._last_at is not None:
            dt = now - self._last_at
            if 0.0 < dt <= MAX_INTEGRATION_STEP:
                # trapezoid between the previous and this velocity
                self._xy = (
                    self._xy[0] + 0.5 * (self.velocity[0] + v[0]) * dt,
                    self._xy[1] + 0.5 * (self.velocity[1] + v[1]) * dt,
                )
                if self._last_yaw is not None:
                    step = (yaw - self._last_yaw + math.pi) % (2.0 * math.pi) - math.pi
                    self._yaw_rate = step / dt
        self._last_at, self._last_yaw = now, yaw
        self.velocity = v
        height = self._height(state)
        self.position_enu = (self._xy[0], self._xy[1], height)
        self.battery = state.battery_percent / 100.0
        self.landed.on_state(state.h_cm, state.motor_time_s, now)

    def messages(self, stamp: float) -> tuple[PoseStamped, TwistStamped, TwistStamped]:
        """(pose ENU in ``odom``, velocity_local ENU, velocity_body FLU) of the latest state."""
        position = self.position_enu or (0.0, 0.0, 0.0)
        yaw_rate = Vector3(z=self._yaw_rate)  # yaw rate only (the Tello sends no body rates)
        motion = (position, self.attitude, self.velocity)
        return odometry(self.headers, FRAME_ODOM, stamp, motion, yaw_rate, yaw_rate)

    def battery_message(self, stamp: float) -> BatteryState:
        """BatteryState: percentage 0..1, voltage and current unknown (NaN)."""
        return BatteryState(header=Header(stamp=stamp), percentage=self.battery)
