"""The controller's config schema (strict: unknown keys are errors naming the file and key).

Units: seconds, metres, radians; pixel quantities in reference pixels (see :mod:`errors`).
Per-aircraft files live in ``config/`` (``iris_sim.yaml``, ``tello.yaml``, ``px4_real.yaml``).
"""

from __future__ import annotations

from typing import Annotated, Literal

import msgspec

from dronewrapper.runtime.config_ranges import NonNegative, Positive, Share, check_ranges
from dronewrapper_controller.pid import PidGains

Mode = Literal["follow_color", "follow_person"]
OnExit = Literal["stop", "land"]


class FollowColorConfig(msgspec.Struct, kw_only=True, forbid_unknown_fields=True):
    """Follow-colour: the blob's wanted radius and the forward PID (gain < 0: e_x > 0 = too close).

    Attributes:
        target_radius: wanted enclosing-circle radius in reference px (paper: 10 px at 320 px
            wide, about 5 m from the beacon).
        vx: forward-speed PID on e_x (m/s per unit of e_x).
        best_when_untargeted: follow the best (largest) blob when the tracker names no target
            (the paper's rule; there is one beacon, identity does not matter).
        id_switch_confirm: a new target track id must stay the target this long before the
            drone steers on it (s; 0 = at once: one beacon, identity does not matter).
    """

    target_radius: Positive = 10.0
    best_when_untargeted: bool = True
    id_switch_confirm: NonNegative = 0.0
    vx: PidGains = msgspec.field(default_factory=lambda: PidGains(kp=-0.5, out_limit=1.0))

    def __post_init__(self) -> None:
        check_ranges(self, "follow_color.")


class FollowPersonConfig(msgspec.Struct, kw_only=True, forbid_unknown_fields=True):
    """Follow-person: the wanted share of the image and the forward PID (gain > 0: e_x > 0 = far).

    Attributes:
        area_ratio: total_area / target_area (paper: 20, the person fills 1/20 of the image).
        max_forward_error: bound of e_x (dimensionless) so a far person cannot ask for 8 m/s.
        vx: forward-speed PID on e_x (m/s per unit of e_x).
        best_when_untargeted: follow the best detection when the tracker names no target.
            False (default): while the target is hidden the drone hovers/searches rather than
            jumping to a passer-by (untracked detections still use the best one).
        id_switch_confirm: a new target track id must stay the target this long before the
            drone steers on it (s): a tracker that picks a passer-by for a frame or two
            must not swing the drone towards them.
    """

    area_ratio: Positive = 20.0
    best_when_untargeted: bool = False
    id_switch_confirm: NonNegative = 0.5
    max_forward_error: Positive = 10.0
    vx: PidGains = msgspec.field(default_factory=lambda: PidGains(kp=0.05, out_limit=1.0))

    def __post_init__(self) -> None:
        check_ranges(self, "follow_person.")


class ServoConfig(msgspec.Struct, kw_only=True, forbid_unknown_fields=True):
    """What the pure servo needs (a subset of :class:`Config`).

    Attributes:
        mode: ``follow_color`` or ``follow_person``.
        ref_width: reference image width of the pixel errors (px).
        detection_timeout: detections older than this are stale -> hover (s).
        search_delay: the target left the view (last seen within ``edge_margin`` of the left
            or right border) this long ago -> search (s).
        occlusion_delay: the target vanished inside the image (hidden) this long ago ->
            search (s).
        edge_margin: the outer share of each half of the image counted as its border (0..1).
        lost_hold: a target missing for at most this long keeps the last command (s): a
            detector or tracker dropout of a frame or two is not a loss.
        search_yaw_rate: search turn rate (rad/s).
    """

    mode: Mode = "follow_color"
    ref_width: Positive = 320.0
    detection_timeout: Positive = 0.5
    search_delay: NonNegative = 2.0
    occlusion_delay: NonNegative = 6.0
    lost_hold: NonNegative = 0.3
    edge_margin: Share = 0.25
    search_yaw_rate: NonNegative = 0.3
    follow_color: FollowColorConfig = msgspec.field(default_factory=FollowColorConfig)
    follow_person: FollowPersonConfig = msgspec.field(default_factory=FollowPersonConfig)
    vz: PidGains = msgspec.field(default_factory=lambda: PidGains(kp=0.02, out_limit=0.5))
    yaw_rate: PidGains = msgspec.field(default_factory=lambda: PidGains(kp=0.005, out_limit=0.8))

    def __post_init__(self) -> None:
        check_ranges(self)
        # across two keys, which a Meta cannot say
        if not self.lost_hold <= self.detection_timeout:
            raise ValueError(f"lost_hold must be in [0, detection_timeout], got {self.lost_hold}")


class TakeoffConfig(msgspec.Struct, kw_only=True, forbid_unknown_fields=True):
    """Take-off on start.

    Attributes:
        on_start: take off when the controller starts (False: the aircraft is already flying).
        height: take-off height above the current position (m).
        timeout: give up (and exit with an error) after this many seconds (s).
        wait_ready: a take-off the autopilot refuses (not ready yet: PX4's estimator settling,
            ArduCopter waiting for its GPS fix) is tried again every 2 s for this long (s)
            after the first try; 0 = the first refusal fails.
    """

    on_start: bool = True
    height: Positive = 2.0
    timeout: Positive = 60.0
    wait_ready: Annotated[float, msgspec.Meta(ge=0, le=600)] = 0.0

    def __post_init__(self) -> None:
        check_ranges(self, "takeoff.")


class Config(ServoConfig, kw_only=True, forbid_unknown_fields=True):
    """The controller process's config.

    Attributes (beyond :class:`ServoConfig`):
        aircraft: a label for logs and status (``iris_sim``, ``tello``, ``px4_real``).
        rate_hz: control loop rate (Hz); a new command is computed for each new frame.
        status_rate_hz: ControllerStatus publishing rate (Hz, >= 5).
        ready_timeout: wait this long (s) for the bridge (telemetry) before giving up.
        takeoff: take-off on start.
        on_exit: ``stop`` (send one zero command and stop commanding; the bridge then hovers
            and, after its commander-lost timeout, lands) or ``land`` (land and wait for it).
        land_timeout: how long to wait for the landing on exit (s).
        dry_run: compute the commands and publish them in the status only: no aircraft is
            waited for, taken off, commanded or landed (a desk test with a webcam).
    """

    aircraft: str = "iris_sim"
    rate_hz: Positive = 20.0
    status_rate_hz: Annotated[float, msgspec.Meta(ge=5)] = 10.0
    ready_timeout: Positive = 30.0
    takeoff: TakeoffConfig = msgspec.field(default_factory=TakeoffConfig)
    on_exit: OnExit = "land"
    land_timeout: Positive = 30.0
    dry_run: bool = False

    def __post_init__(self) -> None:
        super().__post_init__()  # its check_ranges covers this subclass's own keys too
