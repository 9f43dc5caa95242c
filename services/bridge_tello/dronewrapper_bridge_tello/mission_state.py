"""What the Tello bridge knows of its envelope and its local mission: the envelope in force and
who set it, the breach monitor, the waypoints, the item being flown and the flight running
them (the rules over it: :mod:`~dronewrapper_bridge_tello.missions`)."""

from __future__ import annotations

import math

from dronewrapper.envelope import Envelope
from dronewrapper.msgs.mission import Waypoint
from dronewrapper_bridge_base.breach import BreachMonitor
from dronewrapper_bridge_base.operation import Operation


class TelloMissions:
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
        self._next_publish = -math.inf
