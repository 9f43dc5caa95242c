"""What the Tello bridge knows of its envelope and its local mission: the envelope in force and
who set it, the breach monitor, the waypoints, the item being flown and the flight running
them (the rules over it: :mod:`~dronewrapper_bridge_tello.missions`)."""

from __future__ import annotations

import math

from dronewrapper.envelope import Envelope
from dronewrapper.msgs.mission import Waypoint, WaypointList
from dronewrapper.msgs.std import Header
from dronewrapper_bridge_base.breach import BreachMonitor
from dronewrapper_bridge_base.envelope_state import Republished
from dronewrapper_bridge_base.operation import Operation


class TelloMissions(Republished):
    """The envelope, the local mission and its progress (see module docstring)."""

    def __init__(self, envelope: Envelope) -> None:
        self.envelope = envelope
        self.set_by = ""  # who set the envelope in force ("": the configured one)
        self.monitor = BreachMonitor()
        self.waypoints: list[Waypoint] = []
        self.current_seq = 0
        self.running: Operation | None = None
        self.paused = False
        self.last_refusal_text = -math.inf

    @property
    def flying(self) -> bool:
        """A mission flight is running (a push or clear must wait for its pause)."""
        return self.running is not None and not self.running.done

    def kept(self, waypoints: list[Waypoint]) -> None:
        """A new mission, flown from its first item."""
        self.waypoints, self.current_seq = list(waypoints), 0

    def listing(self, stamp: float) -> WaypointList:
        """The mission as published (``stamp`` Unix s)."""
        return WaypointList(
            header=Header(stamp=stamp), current_seq=self.current_seq, waypoints=self.waypoints
        )
