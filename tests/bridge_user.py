"""The part of a bridge test rig that is the test's own node: what it watches, how it commands.

:class:`BridgeUser` is a base for a rig dataclass with a ``user`` node field. After init the
rig holds the newest State, ExtendedState, local pose, body velocity and battery (``latest``
handles), every State in arrival order (``states``), and a 20 Hz :class:`SetpointStream`.
"""

from __future__ import annotations

from setpoint_stream import SetpointStream

from dronewrapper.msgs import registry
from dronewrapper.msgs.mavros import PositionTarget
from dronewrapper.runtime import Node


class BridgeUser:
    """The test's node on a bridge's keys: latest telemetry, every State, a setpoint stream."""

    user: Node

    def __post_init__(self) -> None:
        u = self.user
        self.state = u.latest(registry.STATE)
        self.ext = u.latest(registry.EXTENDED_STATE)
        self.pose = u.latest(registry.LOCAL_POSE)
        self.vbody = u.latest(registry.VELOCITY_BODY)
        self.battery = u.latest(registry.BATTERY)
        self.states: list = []
        u.subscribe(registry.STATE, self.states.append)
        self.stream = SetpointStream(u)
        self.setpoints = self.stream.setpoints

    def command(self, target: PositionTarget | None) -> None:
        """Stream ``target`` at 20 Hz from now on, or stop sending (``None``)."""
        self.stream.command(target)

    def close(self) -> None:
        """Stop the setpoint stream."""
        self.stream.close()
