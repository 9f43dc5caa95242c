"""Controller status: what the visual-servoing controller is doing and why."""

from __future__ import annotations

import msgspec

from dronewrapper.msgs.std import Header

# ControllerStatus.state values
CONTROLLER_IDLE = "idle"
CONTROLLER_TAKEOFF = "takeoff"
CONTROLLER_TRACKING = "tracking"
CONTROLLER_HOVER = "hover"  # detections stale or target just lost: hold position
CONTROLLER_SEARCH = "search"  # target lost for longer than the search delay: turn in place
CONTROLLER_LANDING = "landing"


class ControllerStatus(msgspec.Struct, kw_only=True, frozen=True):
    """Published by the controller at >= 5 Hz.

    Attributes:
        header: ``stamp`` is when the status was made.
        mode: ``follow_color`` or ``follow_person``.
        state: one of the CONTROLLER_* values.
        target_visible: the latest fresh detections contain the target.
        target_id: id of the followed detection ("" when none).
        source_stamp: capture stamp of the camera frame behind the last command (0 if none).
        detection_age: seconds since the newest detections were received (inf if never).
        error_x, error_z, error_yaw: the paper's error terms (forward: dimensionless ratio;
            vertical and yaw: pixels).
        cmd_vx, cmd_vz, cmd_yaw_rate: the last command sent (body FLU m/s, m/s, rad/s).
    """

    header: Header = msgspec.field(default_factory=Header)
    mode: str = ""
    state: str = CONTROLLER_IDLE
    target_visible: bool = False
    target_id: str = ""
    source_stamp: float = 0.0
    detection_age: float = float("inf")
    error_x: float = 0.0
    error_z: float = 0.0
    error_yaw: float = 0.0
    cmd_vx: float = 0.0
    cmd_vz: float = 0.0
    cmd_yaw_rate: float = 0.0
