"""The setpoint watchdog every bridge keeps on its commander (pure; time injected, monotonic s).

DESIGN's failsafe contract, the part that does not depend on the aircraft:

* The latest valid setpoint is **fresh** while younger than ``setpoint_timeout`` (default
  0.5 s) and is flown as it is; once it is older it is **stale** and the bridge makes the
  aircraft hover: state ``hold``. A fresh setpoint ends the hold.
* Once a commander has steered (the bridge says when: :attr:`SetpointWatchdog.engaged`), no
  setpoint for ``commander_lost_timeout`` (default 5 s) while airborne means the **commander is
  lost**: the bridge takes ``commander_lost_action`` (``land`` by default, ``return``, or
  ``hold``: keep hovering), once; state ``land`` / ``return`` until the bridge clears it.

How the hover and the action are flown is each bridge's own (a MAVLink bridge streams a
position hold in the autopilot's guided mode and never fights the pilot; a Tello bridge sends
centred sticks and keeps its link alive): their failsafe modules subclass
:class:`SetpointWatchdog` and :class:`WatchdogConfig`. Every state change is queued as a
:class:`Transition` so the bridge logs and publishes it (:meth:`SetpointWatchdog.transitions`).

It watches *how* the commander commands; :mod:`.commander_lease` decides *who* may.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import ClassVar, Generic, TypeVar

from dronewrapper.msgs.mavros import PositionTarget

NONE, HOLD, LAND, RETURN = "", "hold", "land", "return"
ACTIONS = (HOLD, LAND, RETURN)

K = TypeVar("K")  # the bridge's kind of setpoint (velocity, position, ...)


@dataclass(frozen=True)
class WatchdogConfig:
    """Timeouts (s) and the commander-lost action; a bridge lists the actions it can fly in
    ``ACTIONS`` (a subclass's class attribute)."""

    ACTIONS: ClassVar[tuple[str, ...]] = ACTIONS

    setpoint_timeout: float = 0.5
    commander_lost_timeout: float = 5.0
    commander_lost_action: str = LAND

    def __post_init__(self) -> None:
        if self.commander_lost_action not in self.ACTIONS:
            raise ValueError(
                f"commander_lost_action must be one of {', '.join(self.ACTIONS)}, "
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


class SetpointWatchdog(Generic[K]):
    """The latest setpoint, its freshness, and the failsafe state (see module docstring).

    Attributes:
        state: ``""`` (none), ``hold``, ``land`` or ``return``.
        engaged: a commander has steered since the bridge last let the aircraft fly itself
            (take-off, landing, a mode the pilot chose); set by the bridge.
    """

    def __init__(self, config: WatchdogConfig) -> None:
        self.config = config
        self.state = NONE
        self.engaged = False
        self._target: PositionTarget | None = None
        self._kind: K | None = None
        self._last_setpoint = -math.inf
        self._pending: list[Transition] = []

    # ---- the setpoint

    def take_setpoint(self, target: PositionTarget, kind: K, now: float) -> None:
        """Remember a valid setpoint from the commander; it ends a hold."""
        self._target, self._kind, self._last_setpoint = target, kind, now
        if self.state == HOLD:
            self.set_state(NONE, "fresh setpoint")

    def forget_setpoint(self) -> None:
        """Drop the setpoint and the engagement (the aircraft flies a manoeuvre of its own)."""
        self.engaged = False
        self._target, self._kind = None, None
        self._last_setpoint = -math.inf

    @property
    def target(self) -> PositionTarget | None:
        """The latest setpoint, fresh or not (None when none or forgotten)."""
        return self._target

    @property
    def kind(self) -> K | None:
        """The latest setpoint's kind."""
        return self._kind

    @property
    def last_setpoint(self) -> float:
        """When the latest setpoint arrived (-inf: none)."""
        return self._last_setpoint

    def setpoint_age(self, now: float) -> float:
        """Seconds since the last valid setpoint (inf if none)."""
        return now - self._last_setpoint

    def is_fresh(self, now: float) -> bool:
        """True while the latest setpoint is younger than ``setpoint_timeout``."""
        return self._target is not None and self.setpoint_age(now) <= self.config.setpoint_timeout

    def stale_at(self) -> float:
        """When the latest setpoint went (or goes) stale (-inf: none)."""
        return self._last_setpoint + self.config.setpoint_timeout

    # ---- the failsafe state

    def set_state(self, new: str, reason: str) -> None:
        """Change the state (queued as a :class:`Transition` when it changes)."""
        if new != self.state:
            self._pending.append(Transition(self.state, new, reason))
            self.state = new

    def hold(self, detail: str = "") -> None:
        """The setpoint is stale while the bridge is in control: hover (state ``hold``)."""
        if self.state == NONE:
            self.set_state(HOLD, f"no setpoint for {self.config.setpoint_timeout:g} s{detail}")

    def commander_lost(self, now: float, *, in_control: bool, since: float = -math.inf) -> str:
        """The action to take now ("" for none): the configured one, once, when the bridge is in
        control of an airborne aircraft and no setpoint came for ``commander_lost_timeout``
        (counted from the last setpoint or ``since``, whichever is later)."""
        config = self.config
        lost_for = now - max(self._last_setpoint, since)
        if (
            in_control
            and self.state in (NONE, HOLD)
            and lost_for > config.commander_lost_timeout
            and config.commander_lost_action != HOLD
        ):
            self.set_state(
                config.commander_lost_action, f"commander lost: no setpoint for {lost_for:.1f} s"
            )
            return config.commander_lost_action
        return ""

    def transitions(self) -> list[Transition]:
        """The state changes since the last call."""
        out, self._pending = self._pending, []
        return out
