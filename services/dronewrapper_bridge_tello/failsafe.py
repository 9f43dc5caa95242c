"""The failsafe contract of DESIGN.md for a Tello, as a pure state machine (time injected).

A Tello has no flight modes to fight over and hovers by itself on its optical-flow sensor when
the sticks are centred, so the contract is simpler than bridge_mavlink's:

* A fresh setpoint (younger than ``setpoint_timeout``, default 0.5 s) is flown: the node turns
  it into sticks and sends ``rc`` at ``rc_rate_hz``.
* When it goes stale the bridge sends a real stop, ``rc 0 0 0 0``, for ``stop_repeat_s`` (UDP
  may lose one) and the Tello hovers where it is: state ``hold`` (while flying).
* When none has arrived for ``commander_lost_timeout`` (default 5 s) while flying, and a
  commander had steered since the take-off, the bridge lands (``commander_lost_action`` land,
  the default) or keeps hovering (``hold``): the request is issued once, state ``land``.
* Keep-alive: while flying the bridge sends ``rc 0 0 0 0`` whenever it sent nothing for
  ``keepalive_s``, so the Tello never lands on its own 15 s timeout while a user is in control.
  (A killed bridge sends nothing: the Tello's own timeout lands it.)

Every state change is returned as a :class:`Transition` so the node publishes and logs it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from dronewrapper.msgs.mavros import PositionTarget
from dronewrapper_bridge_tello.sticks import Kind

NONE, HOLD, LAND = "", "hold", "land"
ACTIONS = (HOLD, LAND)


@dataclass(frozen=True)
class FailsafeConfig:
    """Timeouts (s) and the commander-lost action (``land`` or ``hold``)."""

    setpoint_timeout: float = 0.5
    commander_lost_timeout: float = 5.0
    commander_lost_action: str = LAND
    stop_repeat_s: float = 0.5
    keepalive_s: float = 3.0

    def __post_init__(self) -> None:
        if self.commander_lost_action not in ACTIONS:
            raise ValueError(
                f"commander_lost_action must be one of {', '.join(ACTIONS)}, "
                f"got {self.commander_lost_action!r}"
            )
        if not 0 < self.setpoint_timeout < self.commander_lost_timeout:
            raise ValueError("need 0 < setpoint_timeout < commander_lost_timeout")
        if not 0 < self.keepalive_s < 15.0:
            raise ValueError("keepalive_s must be in (0, 15): the Tello lands after 15 s")


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
        fly: the fresh setpoint (and its kind) to turn into sticks now, or None.
        stop: send ``rc 0 0 0 0`` now (expiry, or keep-alive).
        request: ``land`` when the bridge must land now.
        transitions: failsafe state changes made this tick.
    """

    fly: tuple[PositionTarget, Kind] | None = None
    stop: bool = False
    request: str | None = None
    transitions: list[Transition] = field(default_factory=list)


class Failsafe:
    """The bridge's stick stream and failsafe state (see module docstring)."""

    def __init__(self, config: FailsafeConfig = FailsafeConfig()) -> None:
        self.config = config
        self.state = NONE
        self.flying = False
        self.engaged = False
        self._target: tuple[PositionTarget, Kind] | None = None
        self._last_setpoint = -math.inf
        self._stale_since = -math.inf
        self._last_sent = -math.inf
        self._pending: list[Transition] = []

    # ---- inputs ----

    def on_setpoint(self, target: PositionTarget, kind: Kind, now: float) -> None:
        """A valid setpoint arrived from a commander."""
        self._target, self._last_setpoint = (target, kind), now
        if self.flying:
            self.engaged = True
        if self.state == HOLD:
            self._set(NONE, "fresh setpoint")

    def on_flying(self, flying: bool) -> None:
        """Whether the Tello is flying (take-off, in the air, landing)."""
        if self.flying and not flying:
            self.engaged = False
            if self.state != NONE:
                self._set(NONE, "landed")
        self.flying = flying

    def on_takeoff_or_land(self) -> None:
        """A take-off or land command: the drone flies it; no commander is steering."""
        self.engaged = False
        self._target = None
        self._last_setpoint = -math.inf

    def on_sent(self, now: float) -> None:
        """The bridge sent a command to the Tello (any: it resets the Tello's 15 s timer)."""
        self._last_sent = now

    def setpoint_age(self, now: float) -> float:
        """Seconds since the last valid setpoint (inf if none)."""
        return now - self._last_setpoint

    def fresh(self, now: float) -> tuple[PositionTarget, Kind] | None:
        """The latest setpoint if fresh, else None."""
        if self._target is not None and self.setpoint_age(now) <= self.config.setpoint_timeout:
            return self._target
        return None

    # ---- output ----

    def _set(self, new: str, reason: str) -> None:
        if new != self.state:
            self._pending.append(Transition(self.state, new, reason))
            self.state = new

    def tick(self, now: float) -> Tick:
        """Decide this tick (``now`` monotonic s)."""
        out = Tick()
        fresh = self.fresh(now)
        cfg = self.config
        if fresh is not None:
            out.fly = fresh
            self._stale_since = -math.inf
        elif self._target is not None:
            if self._stale_since == -math.inf:
                self._stale_since = self._last_setpoint + cfg.setpoint_timeout
            if now - self._stale_since <= cfg.stop_repeat_s:
                out.stop = True
            if self.flying and self.state == NONE:
                self._set(HOLD, f"no setpoint for {cfg.setpoint_timeout:g} s: rc 0 0 0 0, hover")
        if (
            self.flying
            and self.engaged
            and self.state in (NONE, HOLD)
            and self.setpoint_age(now) > cfg.commander_lost_timeout
            and cfg.commander_lost_action == LAND
        ):
            self._set(LAND, f"commander lost: no setpoint for {self.setpoint_age(now):.1f} s")
            out.request = LAND
        if self.flying and out.fly is None and now - self._last_sent >= cfg.keepalive_s:
            out.stop = True  # keep-alive
        out.transitions, self._pending = self._pending, []
        return out
