"""What the MAVLink bridge knows of missions besides its envelope and home (bridge_base's
:class:`~dronewrapper_bridge_base.envelope_state.EnvelopeState`, which it extends): the
mission the autopilot holds, the item being flown and reached, the rally points, and the
autopilot's return and fence parameters as last written (the rules over it:
:mod:`~dronewrapper_bridge_mavlink.missions`; those parameters:
:mod:`~dronewrapper_bridge_mavlink.autopilot_limits`)."""

from __future__ import annotations

from dataclasses import dataclass, field

import msgspec

from dronewrapper.envelope import Envelope
from dronewrapper.msgs.mission import Waypoint, WaypointList
from dronewrapper.msgs.std import Header
from dronewrapper_bridge_base.envelope_state import EnvelopeState


@dataclass
class Limits:
    """What the bridge last wrote: for which (autopilot, envelope), and a problem ("" none)."""

    written_for: tuple[str, Envelope] | None = None
    problem: str = ""
    running: bool = False
    absent: set[tuple[str, str]] = field(default_factory=set)  # (autopilot, name) unanswered


class MissionState(EnvelopeState):
    """What the bridge knows about missions, home and its envelope (see module docstring)."""

    def __init__(self, envelope: Envelope) -> None:
        super().__init__(envelope)
        self.home_known = False  # HOME_POSITION has arrived (home_local is the origin before)
        self.limits = Limits()  # the autopilot's return and fence parameters
        self.waypoints: list[Waypoint] = []
        self.rally: list[Waypoint] = []  # the rally points last uploaded (global frames)
        self.current_seq = 0
        self.last_reached = -1  # the item last reported on mission/reached

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

    def downloaded(self, waypoints: list[Waypoint]) -> None:
        """The autopilot's mission as downloaded from it (the item flown as it said)."""
        self.waypoints = waypoints

    def cleared(self) -> None:
        """The autopilot holds no mission now."""
        self.waypoints = []
        self.current_seq = 0

    def started(self) -> None:
        """The mission is started afresh: no item reached yet."""
        self.last_reached = -1

    def listing(self, stamp: float) -> WaypointList:
        """The mission as published (``stamp`` Unix s), the item being flown marked."""
        return WaypointList(
            header=Header(stamp=stamp),
            current_seq=self.current_seq,
            waypoints=[
                msgspec.structs.replace(wp, is_current=i == self.current_seq)
                for i, wp in enumerate(self.waypoints)
            ],
        )
