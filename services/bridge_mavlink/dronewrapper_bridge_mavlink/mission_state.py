"""What the MAVLink bridge knows of missions, home and its envelope, and the refusals the envelope
makes of a take-off or a guided mode (the rules over it: :mod:`~dronewrapper_bridge_mavlink.
missions`; the autopilot's return and fence parameters it keeps in step:
:mod:`~dronewrapper_bridge_mavlink.autopilot_limits`)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from dronewrapper import envelope as env
from dronewrapper.envelope import Envelope, EnvelopeError
from dronewrapper.msgs.mission import Waypoint
from dronewrapper.runtime import ServiceError
from dronewrapper_bridge_base.breach import BreachMonitor
from dronewrapper_bridge_mavlink.modes import is_guided


@dataclass
class Limits:
    """What the bridge last wrote: for which (autopilot, envelope), and a problem ("" none)."""

    written_for: tuple[str, Envelope] | None = None
    problem: str = ""
    running: bool = False
    absent: set[tuple[str, str]] = field(default_factory=set)  # (autopilot, name) unanswered


class MissionState:
    """What the bridge knows about missions, home and its envelope (see module docstring)."""

    def __init__(self, envelope: Envelope) -> None:
        self.envelope = envelope
        self.set_by = ""  # who set the envelope in force ("": the configured one)
        self.monitor = BreachMonitor()
        self.home_local: tuple[float, float, float] = (0.0, 0.0, 0.0)  # ENU m
        self.home_known = False  # HOME_POSITION has arrived (home_local is the origin before)
        self.limits = Limits()  # the autopilot's return and fence parameters
        self.home_geo: tuple[float, float, float] | None = None  # deg, deg, m AMSL
        self.waypoints: list[Waypoint] = []
        self.rally: list[Waypoint] = []  # the rally points last uploaded (global frames)
        self.current_seq = 0
        self.last_reached = -1  # the item last reported on mission/reached
        self.last_refusal_text = -math.inf
        self._next_publish = -math.inf

    def on_home(
        self, local: tuple[float, float, float], geo: tuple[float, float, float]
    ) -> tuple[bool, bool]:
        """Home heard, in local ENU m and geodetic (deg, deg, m AMSL): whether it moved, and
        whether it is the first home heard (the autopilot's limits then follow the envelope)."""
        first = self.home_geo is None
        moved = (local, geo) != (self.home_local, self.home_geo)
        self.home_local, self.home_geo, self.home_known = local, geo, True
        return moved, first

    def on_current(self, number: int) -> bool:
        """The item being flown is the bridge's ``number`` now; whether that changed."""
        changed = number != self.current_seq
        self.current_seq = number
        return changed

    def on_reached(self, number: int) -> bool:
        """The autopilot reports the bridge's item ``number`` reached; whether it is news (each
        item is told once: PX4 repeats the report)."""
        if number == self.last_reached:
            return False
        self.last_reached = number
        return True

    def new_mission(self, waypoints: list[Waypoint]) -> None:
        """The autopilot took ``waypoints``: flown from the first, none reached yet."""
        self.waypoints = waypoints
        self.current_seq = 0
        self.last_reached = -1

    def refuse_takeoff(self, height: float) -> None:
        """ServiceError (refused) when a take-off to ``height`` m climbs above the envelope."""
        try:
            env.check_takeoff(self.envelope, height)
        except EnvelopeError as exc:
            raise ServiceError(str(exc), "refused") from None

    def refuse_mode(self, mode: str) -> None:
        """ServiceError (refused) for the guided mode while the aircraft is outside the
        envelope (its breach action must not be undone by a commander's mode change; once
        back inside, the guided mode may be entered again)."""
        if is_guided(mode) and self.monitor.outside:
            raise ServiceError(
                f"{mode} refused: the aircraft is outside the envelope (breach action "
                f"{self.envelope.breach_action} in progress)",
                "refused",
            )
