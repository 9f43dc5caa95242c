"""The failsafe contract of docs/design.md for an autopilot with a guided mode, PX4's OFFBOARD or
ArduPilot's GUIDED, whatever the link (pure; time injected, s): bridge_mavlink's and
bridge_px4_zenoh's.

The aircraft-independent part (setpoint fresh or stale, commander lost, the lost action, the
config's shape) is the shared
:mod:`~dronewrapper_bridge_base.setpoint_watchdog`; this module adds what
a guided mode needs: priming, the bridge's own hold, and never fighting the pilot.

What the bridge streams to the autopilot each tick, and when it acts on its own:

* A fresh setpoint (younger than ``setpoint_timeout``, default 0.5 s) is forwarded as it is.
* When setpoints go stale while the autopilot is in its guided mode (OFFBOARD / GUIDED), the
  bridge streams a position hold: at the pose where a velocity command expired, or at the last
  position target. State ``hold``.
* When none has arrived for ``commander_lost_timeout`` (default 5 s) while airborne in the
  guided mode, it asks the autopilot to ``land`` (or ``return``; ``hold`` keeps hovering). That
  request is issued once; the state stays until the vehicle disarms or the guided mode is
  requested again.
* Never fight the pilot: the bridge acts only while the autopilot is in its guided mode. If the
  autopilot leaves it for a mode the bridge did not ask for, that is reported (an event) and the
  bridge neither switches back nor acts on commander loss until the guided mode is back: when
  someone (the bridge or a ground station) re-enters it, the contract applies again as soon as
  a commander streams (at once if one still is).
* Priming (PX4's OFFBOARD only): before the bridge asks for OFFBOARD it must have streamed for
  > 1 s; while priming it streams the fresh setpoint or, without one, a hold at the current
  pose. Priming ends the moment the mode is confirmed (then the primed stream goes on as the
  engaged stream) or a take-off is requested.
* The bridge's own hold (its take-off in PX4's OFFBOARD): while nobody steers, the bridge
  streams the position it was told to hold (:meth:`Failsafe.hold_at`: the ground before arming,
  then the height asked), so PX4 stays in OFFBOARD and the aircraft holds there as ArduPilot's
  and the Tello's do by themselves after their take-off. No commander is lost meanwhile: none
  has steered. It ends when a commander steers, the autopilot leaves the guided mode or
  disarms, or the bridge lets it go (:meth:`Failsafe.release_hold`).
* Engagement: the hold stream and the commander-lost action apply once a commander has steered
  in the guided mode (a setpoint arrived while in it, it was entered with a fresh setpoint, or
  the bridge entered it with a primed stream). So an autopilot's own take-off in GUIDED
  (ArduPilot's NAV_TAKEOFF) is never overridden by a hold at the ground, and a vehicle nobody
  commanded is left to the autopilot. On the ground, holds are streamed only in PX4's OFFBOARD
  (which needs the stream to stay in the mode and to arm); in ArduPilot's GUIDED a position
  target would override a take-off, so the hold starts once the vehicle is airborne.

Every state change is returned as a :class:`~.setpoint_watchdog.Transition` so the node
publishes and logs it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from dronewrapper.msgs.geometry import Point
from dronewrapper.msgs.mavros import (
    FRAME_LOCAL_NED,
    LANDED_STATE_IN_AIR,
    LANDED_STATE_LANDING,
    LANDED_STATE_TAKEOFF,
    LANDED_STATE_UNDEFINED,
    MASK_POSITION,
    PositionTarget,
)
from dronewrapper_bridge_base import setpoint_watchdog as watchdog
from dronewrapper_bridge_base.setpoint_limits import Kind

__all__ = [
    "GUIDED_MODES",
    "Failsafe",
    "FailsafeConfig",
    "Tick",
    "hold_target",
    "holds_on_the_ground",
    "is_airborne",
    "is_guided",
]

GUIDED_MODES = frozenset({"OFFBOARD", "GUIDED", "GUIDED_NOGPS"})
"""The modes (as State shows them) in which an autopilot flies external setpoints."""


def is_guided(mode: str) -> bool:
    """True in a mode where the autopilot follows external setpoints (OFFBOARD, GUIDED)."""
    return mode in GUIDED_MODES


def holds_on_the_ground(mode: str) -> bool:
    """True in a guided mode where a position hold streamed on the ground is safe and needed:
    PX4's OFFBOARD (no stream, no mode, no arming). Not ArduCopter's GUIDED, where a position
    target overrides NAV_TAKEOFF and keeps the vehicle on the ground until it disarms."""
    return mode == "OFFBOARD"


def hold_target(position_enu: tuple[float, float, float], yaw_enu: float) -> PositionTarget:
    """A position + yaw PositionTarget (mask 3064, ENU) that holds ``position_enu``."""
    x, y, z = position_enu
    return PositionTarget(
        coordinate_frame=FRAME_LOCAL_NED,
        type_mask=MASK_POSITION,
        position=Point(x=x, y=y, z=z),
        yaw=yaw_enu,
    )


@dataclass(frozen=True)
class FailsafeConfig(watchdog.WatchdogConfig):
    """The watchdog's timeouts (s) and lost action (``hold``, ``land``, ``return``), and how long a
    mode change the bridge asked for counts as expected (s)."""

    expected_mode_window: float = 15.0


@dataclass
class Tick:
    """What to do this tick.

    Attributes:
        send: the PositionTarget (ENU/FLU) to stream now, or None to send nothing.
        request: ``land`` or ``return`` when the bridge must ask the autopilot for it now.
        transitions: failsafe state changes made this tick.
        events: things to report (e.g. the pilot took the vehicle out of the guided mode).
    """

    send: PositionTarget | None = None
    request: str | None = None
    transitions: list[watchdog.Transition] = field(default_factory=list)
    events: list[str] = field(default_factory=list)


def is_airborne(landed_state: int, armed: bool) -> bool:
    """In the air per EXTENDED_SYS_STATE (armed when the landed state is unknown)."""
    if landed_state == LANDED_STATE_UNDEFINED:
        return armed
    return landed_state in (LANDED_STATE_IN_AIR, LANDED_STATE_TAKEOFF, LANDED_STATE_LANDING)


class Failsafe(watchdog.SetpointWatchdog[Kind]):
    """The bridge's setpoint stream and failsafe state (see module docstring)."""

    config: FailsafeConfig

    def __init__(self, config: FailsafeConfig = FailsafeConfig()) -> None:
        super().__init__(config)
        self.mode = ""
        self.armed = False
        self.airborne = False
        self.pilot_override = False
        self._guided_since = -math.inf
        self._hold: PositionTarget | None = None
        self._own: PositionTarget | None = None  # the bridge's own hold (hold_at)
        self._prime_until = -math.inf
        self._requested: dict[str, float] = {}
        self._events: list[str] = []

    # ---- inputs ----

    def on_setpoint(self, target: PositionTarget, kind: Kind, now: float) -> None:
        """A valid setpoint arrived from a commander."""
        if is_guided(self.mode) and not self.pilot_override:
            self.engaged = True
            self._own = None  # a commander steers: the bridge's own hold ends
        self.take_setpoint(target, kind, now)

    def fresh_target(self, now: float) -> PositionTarget | None:
        """The latest setpoint if it is fresh, else None."""
        return self.target if self.is_fresh(now) else None

    def on_mode_requested(self, mode: str, now: float) -> None:
        """The bridge itself asked for ``mode`` (a service call or a failsafe action)."""
        self._requested[mode] = now
        if is_guided(mode):
            self.pilot_override = False
            if self.state in (watchdog.LAND, watchdog.RETURN):
                self.set_state(watchdog.NONE, f"{mode} requested")

    def hold_at(self, target: PositionTarget) -> None:
        """Stream ``target`` (a position hold) on the bridge's own account while the autopilot
        is in its guided mode and no commander steers (see module docstring)."""
        self.forget_setpoint()
        self._own = target

    def release_hold(self) -> None:
        """Stop the bridge's own hold."""
        self._own = None

    def on_takeoff_requested(self, now: float) -> None:
        """The autopilot flies its own take-off now: the bridge stays out until commanded
        (no priming, no hold: a hold at the ground would override the take-off)."""
        self.engaged = False
        self._hold = self._own = None
        self._prime_until = min(self._prime_until, now)

    def start_priming(self, now: float, duration: float) -> None:
        """Stream for ``duration`` s from now (fresh setpoint, else a hold) before OFFBOARD."""
        self._prime_until = now + duration
        self._hold = None

    def priming(self, now: float) -> bool:
        """True while a priming stream is running."""
        return now < self._prime_until

    def end_priming(self, now: float, *, engage: bool) -> None:
        """The requested mode is confirmed (or refused): stop priming. With ``engage``, the
        primed stream goes on as the engaged stream if the autopilot is now in its guided mode
        (the bridge entered it holding the pose: PX4 must not lose its OFFBOARD stream)."""
        self._prime_until = min(self._prime_until, now)
        if engage and is_guided(self.mode) and not self.pilot_override:
            self.engaged = True

    def on_vehicle(self, *, mode: str, armed: bool, airborne: bool, now: float) -> None:
        """The autopilot's latest mode, arming and landed state."""
        old_mode = self.mode
        if mode != old_mode:
            if is_guided(mode):
                self._guided_since = now
                if not is_guided(old_mode):
                    self.pilot_override = False  # handed back: the contract applies again
                self.engaged = self.fresh_target(now) is not None
            else:
                self.engaged = False
            left_guided = is_guided(old_mode) and not is_guided(mode)
            if left_guided and not self._expected(mode, now):
                self.pilot_override = True
                self._events.append(
                    f"autopilot left {old_mode} for {mode} without a request from the bridge: "
                    "not switching back"
                )
            if left_guided and self.state == watchdog.HOLD:
                self.set_state(watchdog.NONE, f"the autopilot is in {mode}")
        self.mode, self.airborne = mode, airborne
        if self.armed and not armed and self.state != watchdog.NONE:
            self.set_state(watchdog.NONE, "disarmed")
        if not is_guided(mode) or (self.armed and not armed):
            self._own = None
        self.armed = armed

    def _expected(self, mode: str, now: float) -> bool:
        at = self._requested.get(mode)
        return at is not None and now - at <= self.config.expected_mode_window

    # ---- output ----

    def _hold_here(self, pose: tuple[tuple[float, float, float], float] | None) -> None:
        if self._hold is not None:
            return
        if self.kind is Kind.POSITION and self.target is not None:
            self._hold = self.target
        elif pose is not None:
            self._hold = hold_target(pose[0], pose[1])

    def tick(self, now: float, pose: tuple[tuple[float, float, float], float] | None) -> Tick:
        """Decide this tick. ``pose`` is the current (position ENU m, yaw ENU rad) or None."""
        out = Tick()
        fresh = self.fresh_target(now)
        in_control = is_guided(self.mode) and not self.pilot_override and self.engaged
        if fresh is not None:
            self._hold = None
            out.send = fresh
        elif self.priming(now) or (
            in_control
            and self.state in (watchdog.NONE, watchdog.HOLD)
            and (self.airborne or holds_on_the_ground(self.mode))
        ):
            self._hold_here(pose)
            out.send = self._hold
            if in_control and self.armed:
                self.hold()
        elif in_control and self.state in (watchdog.LAND, watchdog.RETURN):
            self._hold_here(pose)  # until the autopilot has switched mode
            out.send = self._hold
        elif self._own is not None and is_guided(self.mode) and not self.engaged:
            out.send = self._own
        action = self.commander_lost(
            now,
            in_control=in_control and self.airborne,
            since=max(self._guided_since, self._prime_until),
        )
        if action:
            out.request = action
        out.transitions = self.transitions()
        out.events, self._events = self._events, []
        return out
