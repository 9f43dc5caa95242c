"""The control loop's bookkeeping (pure): when to send a command and what the status says.

The node wakes on every new detections message (and at least every ``1 / rate_hz`` s for the
timeouts), calls :meth:`ControlLoop.tick` and sends the command it returns, if any:

- tracking: one command per new camera frame, stamped with that frame's capture stamp (the
  SDK re-publishes it at >= 20 Hz until the next one);
- hover / search: one command when the state (or the search direction) changes.
"""

from __future__ import annotations

import math

from dronewrapper.msgs.control import CONTROLLER_TRACKING, ControllerStatus
from dronewrapper.msgs.std import Header
from dronewrapper.msgs.vision import Detections
from dronewrapper_controller.config import ServoConfig
from dronewrapper_controller.servo import Command, Servo


class ControlLoop:
    """The servo plus "has this command been sent yet" and the status it reports."""

    def __init__(self, config: ServoConfig) -> None:
        self.config = config
        self.servo = Servo(config)
        self.sent: Command | None = None
        self.sent_count = 0
        self.detection_age = math.inf

    def tick(self, now: float, detections: Detections | None, age: float) -> Command | None:
        """The command to send now (None: what was sent last still holds).

        Args:
            now: monotonic time (s).
            detections: the newest detections (None before the first).
            age: seconds since they arrived (inf before the first).
        """
        self.detection_age = age
        cmd = self.servo.step(now, detections, age)
        if self._must_send(cmd):
            self.sent = cmd
            self.sent_count += 1
            return cmd
        return None

    def _must_send(self, cmd: Command) -> bool:
        last = self.sent
        if last is None or last.state != cmd.state:
            return True
        if cmd.state == CONTROLLER_TRACKING:
            return cmd.source_stamp != last.source_stamp
        return (cmd.vx, cmd.vz, cmd.yaw_rate) != (last.vx, last.vz, last.yaw_rate)

    def status(self, wall: float, *, state: str | None = None, seq: int = 0) -> ControllerStatus:
        """The ControllerStatus now (``wall``: Unix time s); ``state`` overrides the servo's
        (``idle``, ``takeoff``, ``landing`` while the node is not servoing)."""
        cmd = self.servo.last
        sent = self.sent
        errors = cmd.errors
        return ControllerStatus(
            header=Header(stamp=wall, frame_id="base_link", seq=seq),
            mode=self.config.mode,
            state=state or cmd.state,
            target_visible=cmd.target_visible,
            target_id=cmd.target_id,
            source_stamp=sent.source_stamp if sent is not None else 0.0,
            detection_age=self.detection_age,
            error_x=errors.x if errors else 0.0,
            error_z=errors.z if errors else 0.0,
            error_yaw=errors.yaw if errors else 0.0,
            cmd_vx=sent.vx if sent is not None and state is None else 0.0,
            cmd_vz=sent.vz if sent is not None and state is None else 0.0,
            cmd_yaw_rate=sent.yaw_rate if sent is not None and state is None else 0.0,
        )
