"""A commander inside a test, like the SDK's 20 Hz setpoint stream, and the yaw of a pose.

:class:`SetpointStream` publishes on ``SETPOINT_RAW_LOCAL`` of a node: each new target at once,
then again every 0.05 s (20 Hz) from its own thread while a target is set, until closed.
"""

from __future__ import annotations

import math
import threading

from dronewrapper.msgs import registry
from dronewrapper.msgs.geometry import PoseStamped
from dronewrapper.msgs.mavros import PositionTarget
from dronewrapper.runtime import Node

PERIOD_S = 0.05
"""Time between two publications of the same target (s): 20 Hz, the SDK's stream rate."""


class SetpointStream:
    """The newest setpoint of a test, re-published at 20 Hz; ``None`` sends nothing."""

    def __init__(self, node: Node) -> None:
        self.setpoints = node.publisher(registry.SETPOINT_RAW_LOCAL)
        self.target: PositionTarget | None = None
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._stream, daemon=True)
        self._thread.start()

    def _stream(self) -> None:
        while not self._stop.wait(PERIOD_S):
            target = self.target
            if target is not None:
                self.setpoints.put(target)

    def command(self, target: PositionTarget | None) -> None:
        """Stream ``target`` from now on (published at once), or stop sending (``None``)."""
        self.target = target
        if target is not None:
            self.setpoints.put(target)

    def close(self) -> None:
        """Stop the stream and wait (up to 2 s) for its thread to end."""
        self._stop.set()
        self._thread.join(2)


def yaw_of(pose: PoseStamped) -> float:
    """The yaw of ``pose``: rotation about z from the frame's x axis (rad, -pi..pi)."""
    q = pose.pose.orientation
    return math.atan2(2 * (q.w * q.z + q.x * q.y), 1 - 2 * (q.y * q.y + q.z * q.z))
