"""The Tello's flight: phases and manoeuvres flown by the shared quadrotor model.

Pure and deterministic: :meth:`TelloFlight.step` is the only way time passes. Frames: local
ENU positions (m), yaw CCW from east (rad), as :mod:`dronewrapper_sim.dynamics`; body-relative
requests (``move``, ``go``, ``curve``, ``rc``) are given forward/left/up in the heading frame.

A manoeuvre (take-off, move, go, curve, rotation, flip, landing) is a *blocking* action:
:meth:`TelloFlight.take_finished` returns True once when it is over, so that the protocol can
answer ``ok`` then. Paths are flown by a carrot that runs along them at the requested speed
(position target plus velocity feed-forward), so a move takes its length / speed plus about a
second to settle, as on the real drone.
"""

from __future__ import annotations

import enum
import math
from dataclasses import dataclass

from dronewrapper_sim import dynamics
from dronewrapper_sim.battery import Battery
from dronewrapper_sim.dynamics import GRAVITY, ControlInput, QuadState, WindModel
from dronewrapper_sim.frames import wrap_pi
from dronewrapper_sim.px4.flight_control import PositionController, Target
from dronewrapper_sim.tello.params import TELLO, TELLO_GAINS, TELLO_QUAD, TelloEnvelope

Vec3 = tuple[float, float, float]


class Phase(enum.Enum):
    """What the Tello is doing."""

    LANDED = "landed"  # motors off on the ground
    TAKING_OFF = "taking_off"
    HOVERING = "hovering"  # holding position (also after rc returns to 0)
    RC = "rc"  # following rc stick velocities
    MOVING = "moving"  # flying a path (move, go, curve)
    ROTATING = "rotating"
    FLIPPING = "flipping"
    LANDING = "landing"
    FALLING = "falling"  # motors stopped in the air (emergency)


FLYING_PHASES = frozenset(
    {Phase.HOVERING, Phase.RC, Phase.MOVING, Phase.ROTATING, Phase.FLIPPING, Phase.TAKING_OFF}
)
BLOCKING_PHASES = frozenset(
    {Phase.TAKING_OFF, Phase.MOVING, Phase.ROTATING, Phase.FLIPPING, Phase.LANDING}
)


@dataclass
class _Path:
    """A polyline flown at ``speed`` (m/s); ``s`` is the carrot's distance along it (m)."""

    points: list[Vec3]
    speed: float
    s: float = 0.0

    def __post_init__(self) -> None:
        self.lengths = [0.0]
        for a, b in zip(self.points, self.points[1:], strict=False):
            self.lengths.append(self.lengths[-1] + math.dist(a, b))

    @property
    def length(self) -> float:
        return self.lengths[-1]

    def advance(self, dt: float) -> None:
        self.s = min(self.s + self.speed * dt, self.length)

    def carrot(self) -> tuple[Vec3, Vec3]:
        """The carrot's position and velocity (ENU m, m/s)."""
        if self.length <= 0.0:
            return self.points[-1], (0.0, 0.0, 0.0)
        i = 1
        while i < len(self.lengths) - 1 and self.lengths[i] < self.s:
            i += 1
        a, b = self.points[i - 1], self.points[i]
        seg = self.lengths[i] - self.lengths[i - 1]
        f = (self.s - self.lengths[i - 1]) / seg if seg > 0 else 1.0
        pos = tuple(a[k] + f * (b[k] - a[k]) for k in range(3))
        if self.s >= self.length or seg <= 0:
            return pos, (0.0, 0.0, 0.0)  # type: ignore[return-value]
        vel = tuple(self.speed * (b[k] - a[k]) / seg for k in range(3))
        return pos, vel  # type: ignore[return-value]

    @property
    def at_end(self) -> bool:
        return self.s >= self.length


def body_to_enu(forward: float, left: float, up: float, yaw: float) -> Vec3:
    """A heading-frame vector (forward, left, up) in ENU for heading ``yaw`` (rad, CCW)."""
    c, s = math.cos(yaw), math.sin(yaw)
    return (c * forward - s * left, s * forward + c * left, up)


class TelloFlight:
    """The simulated Tello's flight state and manoeuvres (see module doc).

    Args:
        start: ENU x, y (m) and yaw (rad) where it rests, motors off.
        envelope: speeds, limits and timings.
        wind: the wind model (None = still air).
        battery_percent: charge at power-on, %.
    """

    def __init__(
        self,
        start: tuple[float, float, float] = (0.0, 0.0, 0.0),
        envelope: TelloEnvelope = TELLO,
        wind: WindModel | None = None,
        battery_percent: float = 100.0,
    ) -> None:
        self.env = envelope
        self.start = start
        self.state = QuadState(x=start[0], y=start[1], yaw=start[2])
        self.origin_yaw = start[2]  # heading at power-on: the Tello's yaw 0 and x axis
        self.controller = PositionController(TELLO_GAINS)
        self.wind = wind or WindModel()
        self.battery = Battery(cells=1, capacity_mah=envelope.capacity_mah, resistance_ohm=0.05)
        self.battery.consumed_mah = envelope.capacity_mah * (1.0 - battery_percent / 100.0)
        self.phase = Phase.LANDED
        self.time_s = 0.0
        self.motor_time_s = 0.0  # motors on, s (the state string's ``time``)
        self.ground_z = 0.0
        self._path: _Path | None = None
        self._yaw_target: float = start[2]
        self._yaw_to_go = 0.0  # remaining rotation of cw/ccw, rad (signed, CCW > 0)
        self._hold: Vec3 | None = None
        self._rc = (0.0, 0.0, 0.0, 0.0)  # forward, left, up (m/s), yaw rate (rad/s CCW)
        self._phase_t0 = 0.0
        self._finished = False

    # ---- queries ----

    @property
    def flying(self) -> bool:
        """Motors on and in the air (or taking off)."""
        return self.phase in FLYING_PHASES

    @property
    def busy(self) -> bool:
        """A blocking manoeuvre is under way."""
        return self.phase in BLOCKING_PHASES

    @property
    def motors_on(self) -> bool:
        return self.phase not in (Phase.LANDED, Phase.FALLING)

    @property
    def battery_percent(self) -> int:
        return round(self.battery.remaining * 100.0)

    def take_finished(self) -> bool:
        """True once after a blocking manoeuvre has finished."""
        done, self._finished = self._finished, False
        return done

    # ---- commands (validated by the protocol; these assume sane values) ----

    def reset_to_start(self) -> None:
        """Back at the start pose, on the ground, motors off, at rest (the battery stays)."""
        self.state = QuadState(x=self.start[0], y=self.start[1], yaw=self.start[2])
        self.controller = PositionController(TELLO_GAINS)
        self.phase = Phase.LANDED
        self.ground_z = 0.0
        self._path = None
        self._hold = None
        self._rc = (0.0, 0.0, 0.0, 0.0)
        self._yaw_target = self.start[2]
        self._yaw_to_go = 0.0
        self._finished = False

    def takeoff(self) -> None:
        """Spin up and climb to the take-off height; blocking."""
        s = self.state
        self.ground_z = s.z
        self._enter(Phase.TAKING_OFF)
        top = (s.x, s.y, self.ground_z + self.env.takeoff_height)
        self._path = _Path([(s.x, s.y, s.z), top], self.env.takeoff_speed)
        self._yaw_target = s.yaw

    def land(self) -> None:
        """Descend at the landing speed until the ground stops it, then motors off; blocking."""
        s = self.state
        self._enter(Phase.LANDING)
        self._path = _Path([(s.x, s.y, s.z), (s.x, s.y, s.z - 50.0)], self.env.land_speed)
        self._yaw_target = s.yaw

    def emergency(self) -> None:
        """Stop the motors at once: it falls if flying."""
        self._path = None
        self._enter(Phase.LANDED if self.state.on_ground else Phase.FALLING)

    def hover(self) -> None:
        """Stop whatever it does and hold position (``stop``; rc 0 0 0 0)."""
        if self.flying:
            self._enter(Phase.HOVERING)
            self._hold = None
            self._yaw_target = self.state.yaw

    def move(self, forward: float, left: float, up: float, speed: float) -> None:
        """Fly a straight line relative to the heading (m) at ``speed`` (m/s); blocking."""
        s = self.state
        d = body_to_enu(forward, left, up, s.yaw)
        start = self._anchor()
        self.fly_path([start, (start[0] + d[0], start[1] + d[1], start[2] + d[2])], speed)

    def fly_path(self, points: list[Vec3], speed: float) -> None:
        """Fly a polyline of ENU points (m) at ``speed`` (m/s); blocking."""
        self._enter(Phase.MOVING)
        self._path = _Path(points, speed)
        self._yaw_target = self.state.yaw

    def rotate(self, angle_ccw: float) -> None:
        """Turn by ``angle_ccw`` (rad, CCW > 0) at the rotation rate; blocking."""
        self._hold = self._anchor()
        self._enter(Phase.ROTATING)
        self._yaw_to_go = angle_ccw
        self._yaw_target = self.state.yaw

    def flip(self) -> None:
        """A flip: the airframe loops and comes back where it was (lasts ``flip_s``); blocking."""
        self._hold = self._anchor()
        self._enter(Phase.FLIPPING)

    def set_rc(self, right: float, forward: float, up: float, yaw_cw: float) -> None:
        """Stick inputs -1..1 (rc a/100, b/100, c/100, d/100): velocities in the heading frame."""
        env = self.env
        if right == forward == up == yaw_cw == 0.0:
            if self.phase is Phase.RC:
                self.hover()
            return
        self._rc = (
            forward * env.rc_max_xy,
            -right * env.rc_max_xy,
            up * env.rc_max_z,
            -yaw_cw * env.rc_max_yaw_rate,
        )
        if self.phase is not Phase.RC:
            self._enter(Phase.RC)

    # ---- time ----

    def step(self, dt: float) -> None:
        """Advance ``dt`` seconds: manoeuvre, controller, physics, battery."""
        self.time_s += dt
        target = self._target(dt)
        control = self.controller.update(target, self.state, dt)
        if not self.motors_on or target.idle:
            control = ControlInput()
        self.state = dynamics.step(self.state, control, TELLO_QUAD, dt, self.wind.step(dt))
        if self.motors_on:
            self.motor_time_s += dt
        load = max(0.0, self.state.thrust / GRAVITY)
        current = self.env.idle_current_a + (self.env.hover_current_a * load**1.5)
        self.battery.step(current, dt)
        self._check_done()

    # ---- internals ----

    def _enter(self, phase: Phase) -> None:
        was_busy = self.busy
        self.phase = phase
        self._phase_t0 = self.time_s
        if was_busy and phase not in BLOCKING_PHASES:
            self._finished = False  # preempted: the old manoeuvre never finishes

    def _anchor(self) -> Vec3:
        """Where the Tello is meant to be: the hold point, else where it is."""
        s = self.state
        if self.phase in (Phase.HOVERING, Phase.ROTATING) and self._hold is not None:
            return self._hold
        return (s.x, s.y, s.z)

    def _finish(self, phase: Phase) -> None:
        s = self.state
        self.phase = phase
        self._path = None
        self._hold = (s.x, s.y, s.z) if phase is Phase.HOVERING else None
        self._finished = True

    def _target(self, dt: float) -> Target:
        s, env = self.state, self.env
        phase = self.phase
        if phase in (Phase.LANDED, Phase.FALLING):
            return Target(idle=True)
        if phase is Phase.TAKING_OFF and self.time_s - self._phase_t0 < env.spool_up_s:
            return Target(idle=True)
        if phase in (Phase.TAKING_OFF, Phase.MOVING, Phase.LANDING) and self._path is not None:
            self._path.advance(dt)
            pos, vel = self._path.carrot()
            return Target(
                position=pos,
                velocity=vel,
                yaw=self._yaw_target,
                max_xy=self._path.speed + 0.5,
                max_up=max(self._path.speed, 0.5) + 0.5,
                max_down=max(self._path.speed, 0.5) + 0.5,
            )
        if phase is Phase.ROTATING:
            turn = math.copysign(min(abs(self._yaw_to_go), env.rotate_rate * dt), self._yaw_to_go)
            self._yaw_to_go -= turn
            self._yaw_target = wrap_pi(self._yaw_target + turn)
            return Target(position=self._hold or (s.x, s.y, s.z), yaw=self._yaw_target)
        if phase is Phase.RC:
            fwd, left, up, yaw_rate = self._rc
            vx, vy, vz = body_to_enu(fwd, left, up, s.yaw)
            return Target(velocity=(vx, vy, vz), yaw_rate=yaw_rate, max_xy=env.rc_max_xy)
        # hovering, flipping: hold a point (once slow enough to pick one)
        if self._hold is None and math.hypot(s.vx, s.vy, s.vz) < env.settle_speed:
            self._hold = (s.x, s.y, s.z)
        if self._hold is None:
            return Target(velocity=(0.0, 0.0, 0.0), yaw=self._yaw_target)
        return Target(position=self._hold, yaw=self._yaw_target)

    def _check_done(self) -> None:
        s, env = self.state, self.env
        phase = self.phase
        slow = math.hypot(s.vx, s.vy, s.vz) < env.settle_speed
        if phase is Phase.FALLING and s.on_ground:
            self.phase = Phase.LANDED
        elif phase is Phase.LANDING and s.on_ground and self.time_s - self._phase_t0 > 0.2:
            self._finish(Phase.LANDED)
        elif phase in (Phase.TAKING_OFF, Phase.MOVING) and self._path is not None:
            end = self._path.points[-1]
            near = math.dist((s.x, s.y, s.z), end) < env.arrive_m
            if self._path.at_end and near and slow:
                self._finish(Phase.HOVERING)
        elif phase is Phase.ROTATING:
            if self._yaw_to_go == 0.0 and abs(wrap_pi(self._yaw_target - s.yaw)) < env.arrive_yaw:
                self._finish(Phase.HOVERING)
        elif phase is Phase.FLIPPING and self.time_s - self._phase_t0 >= env.flip_s:
            self._finish(Phase.HOVERING)
