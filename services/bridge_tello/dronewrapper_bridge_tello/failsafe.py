"""The failsafe contract of docs/design.md for a Tello, as a pure state machine (time injected).

The aircraft-independent part (setpoint fresh or stale, commander lost, the lost action, the
config's shape) is the shared
:mod:`~dronewrapper_bridge_base.setpoint_watchdog`; this module adds what
is the Tello's: the repeated stop and the keep-alive.

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
from typing import ClassVar

from dronewrapper.msgs.mavros import PositionTarget
from dronewrapper_bridge_base.setpoint_watchdog import (
    HOLD,
    LAND,
    NONE,
    SetpointWatchdog,
    Transition,
    WatchdogConfig,
)
from dronewrapper_bridge_tello.sticks import Kind

ACTIONS = (HOLD, LAND)
__all__ = ["ACTIONS", "HOLD", "LAND", "NONE", "Failsafe", "FailsafeConfig", "Tick", "Transition"]


@dataclass(frozen=True)
class FailsafeConfig(WatchdogConfig):
    """The watchdog's timeouts (s) and lost action (``land`` or ``hold``: a Tello has no return),
    how long the stop is repeated (s) and the keep-alive period (s, under the Tello's 15 s)."""

    ACTIONS: ClassVar[tuple[str, ...]] = ACTIONS

    stop_repeat_s: float = 0.5
    keepalive_s: float = 3.0

    def __post_init__(self) -> None:
        super().__post_init__()
        if not 0 < self.keepalive_s < 15.0:
            raise ValueError("keepalive_s must be in (0, 15): the Tello lands after 15 s")


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


class Failsafe(SetpointWatchdog[Kind]):
    """The bridge's stick stream and failsafe state (see module docstring)."""

    config: FailsafeConfig

    def __init__(self, config: FailsafeConfig = FailsafeConfig()) -> None:
        super().__init__(config)
        self.flying = False
        self._last_sent = -math.inf

    # ---- inputs ----

    def on_setpoint(self, target: PositionTarget, kind: Kind, now: float) -> None:
        """A valid setpoint arrived from a commander."""
        if self.flying:
            self.engaged = True
        self.take_setpoint(target, kind, now)

    def on_flying(self, flying: bool) -> None:
        """Whether the Tello is flying (take-off, in the air, landing)."""
        if self.flying and not flying:
            self.engaged = False
            self.set_state(NONE, "landed")
        self.flying = flying

    def on_takeoff_or_land(self) -> None:
        """A take-off or land command: the drone flies it; no commander is steering."""
        self.forget_setpoint()

    def on_sent(self, now: float) -> None:
        """The bridge sent a command to the Tello (any: it resets the Tello's 15 s timer)."""
        self._last_sent = now

    def fresh(self, now: float) -> tuple[PositionTarget, Kind] | None:
        """The latest setpoint (and its kind) if fresh, else None."""
        if self.is_fresh(now) and self.target is not None and self.kind is not None:
            return self.target, self.kind
        return None

    # ---- output ----

    def tick(self, now: float) -> Tick:
        """Decide this tick (``now`` monotonic s)."""
        out = Tick()
        fresh = self.fresh(now)
        cfg = self.config
        if fresh is not None:
            out.fly = fresh
        elif self.target is not None:
            if now - self.stale_at() <= cfg.stop_repeat_s:
                out.stop = True  # a real stop, repeated: UDP may lose one
            if self.flying:
                self.hold(": rc 0 0 0 0, hover")
        if self.commander_lost(now, in_control=self.flying and self.engaged) == LAND:
            out.request = LAND
        if self.flying and out.fly is None and now - self._last_sent >= cfg.keepalive_s:
            out.stop = True  # keep-alive
        out.transitions = self.transitions()
        return out
