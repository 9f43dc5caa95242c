"""The controller's config schema (strict: unknown keys are errors naming the file and key).

Units: seconds, metres, radians; pixel quantities in reference pixels (see :mod:`errors`).
Per-aircraft files live in ``config/`` (``iris_sim.yaml``, ``tello.yaml``, ``px4_real.yaml``).
"""

from __future__ import annotations

import msgspec

from dronewrapper_controller.pid import PidGains

MODES = ("follow_color", "follow_person")
ON_EXIT = ("stop", "land")


def _positive(name: str, value: float) -> None:
    if not value > 0:
        raise ValueError(f"{name} must be > 0, got {value}")


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

    target_radius: float = 10.0
    best_when_untargeted: bool = True
    id_switch_confirm: float = 0.0
    vx: PidGains = msgspec.field(default_factory=lambda: PidGains(kp=-0.5, out_limit=1.0))

    def __post_init__(self) -> None:
        _positive("follow_color.target_radius", self.target_radius)
        if not self.id_switch_confirm >= 0:
            raise ValueError(
                f"follow_color.id_switch_confirm must be >= 0, got {self.id_switch_confirm}"
            )


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

    area_ratio: float = 20.0
    best_when_untargeted: bool = False
    id_switch_confirm: float = 0.5
    max_forward_error: float = 10.0
    vx: PidGains = msgspec.field(default_factory=lambda: PidGains(kp=0.05, out_limit=1.0))

    def __post_init__(self) -> None:
        _positive("follow_person.area_ratio", self.area_ratio)
        _positive("follow_person.max_forward_error", self.max_forward_error)
        if not self.id_switch_confirm >= 0:
            raise ValueError(
                f"follow_person.id_switch_confirm must be >= 0, got {self.id_switch_confirm}"
            )


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

    mode: str = "follow_color"
    ref_width: float = 320.0
    detection_timeout: float = 0.5
    search_delay: float = 2.0
    occlusion_delay: float = 6.0
    lost_hold: float = 0.3
    edge_margin: float = 0.25
    search_yaw_rate: float = 0.3
    follow_color: FollowColorConfig = msgspec.field(default_factory=FollowColorConfig)
    follow_person: FollowPersonConfig = msgspec.field(default_factory=FollowPersonConfig)
    vz: PidGains = msgspec.field(default_factory=lambda: PidGains(kp=0.02, out_limit=0.5))
    yaw_rate: PidGains = msgspec.field(default_factory=lambda: PidGains(kp=0.005, out_limit=0.8))

    def __post_init__(self) -> None:
        if self.mode not in MODES:
            raise ValueError(f"mode must be one of {', '.join(MODES)}, got {self.mode!r}")
        _positive("ref_width", self.ref_width)
        _positive("detection_timeout", self.detection_timeout)
        if not self.search_delay >= 0:
            raise ValueError(f"search_delay must be >= 0, got {self.search_delay}")
        if not 0 <= self.lost_hold <= self.detection_timeout:
            raise ValueError(f"lost_hold must be in [0, detection_timeout], got {self.lost_hold}")
        if not self.occlusion_delay >= 0:
            raise ValueError(f"occlusion_delay must be >= 0, got {self.occlusion_delay}")
        if not 0.0 <= self.edge_margin <= 1.0:
            raise ValueError(f"edge_margin must be in [0, 1], got {self.edge_margin}")
        if not self.search_yaw_rate >= 0:
            raise ValueError(f"search_yaw_rate must be >= 0, got {self.search_yaw_rate}")


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
    height: float = 2.0
    timeout: float = 60.0
    wait_ready: float = 0.0

    def __post_init__(self) -> None:
        _positive("takeoff.height", self.height)
        _positive("takeoff.timeout", self.timeout)
        if not 0 <= self.wait_ready <= 600:
            raise ValueError(f"takeoff.wait_ready must be in [0, 600] s, got {self.wait_ready}")


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
    rate_hz: float = 20.0
    status_rate_hz: float = 10.0
    ready_timeout: float = 30.0
    takeoff: TakeoffConfig = msgspec.field(default_factory=TakeoffConfig)
    on_exit: str = "land"
    land_timeout: float = 30.0
    dry_run: bool = False

    def __post_init__(self) -> None:
        super().__post_init__()
        _positive("rate_hz", self.rate_hz)
        if not self.status_rate_hz >= 5:
            raise ValueError(f"status_rate_hz must be >= 5, got {self.status_rate_hz}")
        _positive("ready_timeout", self.ready_timeout)
        _positive("land_timeout", self.land_timeout)
        if self.on_exit not in ON_EXIT:
            raise ValueError(f"on_exit must be one of {', '.join(ON_EXIT)}, got {self.on_exit!r}")
