"""The failsafe contract of docs/design.md as a pure state machine (time is injected, monotonic s).

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
* Engagement: the hold stream and the commander-lost action apply once a commander has steered
  in the guided mode (a setpoint arrived while in it, it was entered with a fresh setpoint, or
  the bridge entered it with a primed stream). So an autopilot's own take-off in GUIDED
  (ArduPilot's NAV_TAKEOFF) is never overridden by a hold at the ground, and a vehicle nobody
  commanded is left to the autopilot. On the ground, holds are streamed only in PX4's OFFBOARD
  (which needs the stream to stay in the mode and to arm); in ArduPilot's GUIDED a position
  target would override a take-off, so the hold starts once the vehicle is airborne.

Every state change is returned as a :class:`Transition` so the node publishes and logs it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from dronewrapper.msgs.mavros import (
    LANDED_STATE_IN_AIR,
    LANDED_STATE_LANDING,
    LANDED_STATE_TAKEOFF,
    LANDED_STATE_UNDEFINED,
    PositionTarget,
)
from dronewrapper_bridge_mavlink.modes import holds_on_the_ground, is_guided
from dronewrapper_bridge_mavlink.setpoints import Kind, hold_target

NONE, HOLD, LAND, RETURN = "", "hold", "land", "return"
ACTIONS = (HOLD, LAND, RETURN)


@dataclass(frozen=True)
class FailsafeConfig:
    """Timeouts (s) and what to do when the commander is lost (``hold``, ``land``, ``return``)."""

    setpoint_timeout: float = 0.5
    commander_lost_timeout: float = 5.0
    commander_lost_action: str = LAND
    expected_mode_window: float = 15.0  # s a bridge-requested mode change counts as expected

    def __post_init__(self) -> None:
        if self.commander_lost_action not in ACTIONS:
            raise ValueError(
                f"commander_lost_action must be one of {', '.join(ACTIONS)}, "
                f"got {self.commander_lost_action!r}"
            )
        if not 0 < self.setpoint_timeout < self.commander_lost_timeout:
            raise ValueError("need 0 < setpoint_timeout < commander_lost_timeout")


@dataclass(frozen=True)
class Transition:
    """A failsafe state change (``old`` -> ``new``) and why."""

    old: str
    new: str
    reason: str


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
    transitions: list[Transition] = field(default_factory=list)
    events: list[str] = field(default_factory=list)


def is_airborne(landed_state: int, armed: bool) -> bool:
    """In the air per EXTENDED_SYS_STATE (armed when the landed state is unknown)."""
    if landed_state == LANDED_STATE_UNDEFINED:
        return armed
    return landed_state in (LANDED_STATE_IN_AIR, LANDED_STATE_TAKEOFF, LANDED_STATE_LANDING)


class Failsafe:
    """The bridge's setpoint stream and failsafe state (see module docstring)."""

    def __init__(self, config: FailsafeConfig = FailsafeConfig()) -> None:
        self.config = config
        self.state = NONE
        self.mode = ""
        self.armed = False
        self.airborne = False
        self.pilot_override = False
        self.engaged = False
        self._target: PositionTarget | None = None
        self._kind: Kind | None = None
        self._last_setpoint = -math.inf
        self._guided_since = -math.inf
        self._hold: PositionTarget | None = None
        self._prime_until = -math.inf
        self._requested: dict[str, float] = {}
        self._pending: list[Transition] = []
        self._events: list[str] = []

    # ---- inputs ----

    def on_setpoint(self, target: PositionTarget, kind: Kind, now: float) -> None:
        """A valid setpoint arrived from a commander."""
        self._target, self._kind, self._last_setpoint = target, kind, now
        if is_guided(self.mode) and not self.pilot_override:
            self.engaged = True
        if self.state == HOLD:
            self._set(NONE, "fresh setpoint")

    def setpoint_age(self, now: float) -> float:
        """Seconds since the last valid setpoint (inf if none)."""
        return now - self._last_setpoint

    def fresh_target(self, now: float) -> PositionTarget | None:
        """The latest setpoint if it is fresh, else None."""
        if self._target is not None and self.setpoint_age(now) <= self.config.setpoint_timeout:
            return self._target
        return None

    def on_mode_requested(self, mode: str, now: float) -> None:
        """The bridge itself asked for ``mode`` (a service call or a failsafe action)."""
        self._requested[mode] = now
        if is_guided(mode):
            self.pilot_override = False
            if self.state in (LAND, RETURN):
                self._set(NONE, f"{mode} requested")

    def on_takeoff_requested(self, now: float) -> None:
        """The autopilot flies its own take-off now: the bridge stays out until commanded
        (no priming, no hold: a hold at the ground would override the take-off)."""
        self.engaged = False
        self._hold = None
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
            if left_guided and self.state == HOLD:
                self._set(NONE, f"the autopilot is in {mode}")
        self.mode, self.airborne = mode, airborne
        if self.armed and not armed and self.state != NONE:
            self._set(NONE, "disarmed")
        self.armed = armed

    def _expected(self, mode: str, now: float) -> bool:
        at = self._requested.get(mode)
        return at is not None and now - at <= self.config.expected_mode_window

    # ---- output ----

    def _set(self, new: str, reason: str) -> None:
        if new != self.state:
            self._pending.append(Transition(self.state, new, reason))
            self.state = new

    def _hold_here(self, pose: tuple[tuple[float, float, float], float] | None) -> None:
        if self._hold is not None:
            return
        if self._kind is Kind.POSITION and self._target is not None:
            self._hold = self._target
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
            and self.state in (NONE, HOLD)
            and (self.airborne or holds_on_the_ground(self.mode))
        ):
            self._hold_here(pose)
            out.send = self._hold
            if in_control and self.state == NONE and self.armed:
                self._set(HOLD, f"no setpoint for {self.config.setpoint_timeout:g} s")
        elif in_control and self.state in (LAND, RETURN):
            self._hold_here(pose)  # until the autopilot has switched mode
            out.send = self._hold
        lost_for = now - max(self._last_setpoint, self._guided_since, self._prime_until)
        if (
            in_control
            and self.airborne
            and self.state in (NONE, HOLD)
            and lost_for > self.config.commander_lost_timeout
            and self.config.commander_lost_action != HOLD
        ):
            action = self.config.commander_lost_action
            self._set(action, f"commander lost: no setpoint for {lost_for:.1f} s")
            out.request = action
        out.transitions, self._pending = self._pending, []
        out.events, self._events = self._events, []
        return out
