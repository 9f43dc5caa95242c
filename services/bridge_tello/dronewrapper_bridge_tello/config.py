"""bridge_tello configuration (strict: an unknown key is an error naming it; see README.md)."""

from __future__ import annotations

from typing import Annotated, Literal

import msgspec

from dronewrapper.envelope import Envelope
from dronewrapper.runtime.config_ranges import Positive, check_ranges
from dronewrapper_bridge_base.config_ranges import Attempts, LateSetpoint
from dronewrapper_bridge_tello.failsafe import FailsafeConfig
from dronewrapper_bridge_tello.sticks import StickScale
from dronewrapper_bridge_tello.video_demand import VideoPolicy

TELLO_ENVELOPE = Envelope(
    max_altitude=10.0,
    max_distance=30.0,
    max_horizontal_speed=3.0,
    max_vertical_speed=2.0,
    breach_action="land",
)
"""A Tello's default envelope: 10 m up, 30 m out (its Wi-Fi's reach), land on a breach."""


class Config(msgspec.Struct, kw_only=True, forbid_unknown_fields=True):
    """bridge_tello configuration (units in the names' docs; see README.md)."""

    tello_address: str = "192.168.10.1"  # the Tello (a simulated one: 127.0.0.1)
    command_port: int = 8889
    local_address: str = "0.0.0.0"  # where our three sockets bind
    local_command_port: int = 0  # 0: any
    state_port: int = 8890
    video_port: int = 11111
    # on | off | on_demand (video_demand.py): when to streamon and publish cam_frontal/image_raw
    # (YAML's true/false and on/off read as on/off)
    video: bool | Literal["on", "off", "on_demand"] = "on"
    video_idle_s: float = 10.0  # s the stream runs on after the last subscriber (on_demand)
    video_retry_s: float = 2.0  # s between tries of a refused or unanswered streamon/streamoff
    video_attempts: int = 3  # tries in a row before waiting for a new demand or a reconnection
    compressed: bool = False  # also publish JPEG on image_raw/compressed (else only on request)
    jpeg_quality: Annotated[int, msgspec.Meta(ge=1, le=100)] = 80
    video_chunk: int = 1460  # bytes of a full video datagram (a shorter one ends a frame)
    velocity_frame: Literal["reference", "body_frd"] = "reference"  # the frame of vgx, vgy, vgz
    # ENU yaw of the Tello's power-on heading (deg; 0: local +x)
    reference_yaw_deg: Annotated[float, msgspec.Meta(ge=-360, le=360)] = 0.0
    velocity_unit: float = 0.1  # m/s per vg* unit (the Tello sends dm/s)
    height_source: Literal["h", "tof"] = "h"  # the state string field read as the height
    tof_ground_cm: float = 10.0  # tof reading on the ground
    rc_rate_hz: Annotated[float, msgspec.Meta(ge=20, le=50)] = 20.0  # rc stream while commanded
    setpoint_timeout: float = 0.5  # s: setpoints expire -> rc 0 0 0 0 (hover)
    commander_lost_timeout: float = 5.0  # s without setpoint while flying -> action
    commander_lost_action: str = "land"  # land | hold
    keepalive_s: float = 3.0  # s without any command while flying -> rc 0 0 0 0
    command_timeout: float = 1.0  # s to wait for the reply to a quick command
    command_attempts: Attempts = 3
    takeoff_timeout: float = 20.0  # s: the Tello replies ok once the take-off is over
    land_timeout: float = 20.0
    move_timeout: float = 15.0  # s: up/down after take-off
    link_timeout: float = 1.5  # s without a state string -> disconnected
    reconnect_s: float = 1.0  # s between 'command' attempts while disconnected
    state_rate_hz: Positive = 2.0  # periodic State (also on change)
    extended_state_rate_hz: Positive = 4.0
    battery_rate_hz: Positive = 1.0
    command_lease: bool = (
        False  # obey one commander at a time (dronewrapper_bridge_base.commander_lease)
    )
    command_lease_ttl_s: Positive = 10.0  # s: a silent holder loses the lease
    late_setpoint_s: LateSetpoint = 0.3  # s: refuse a setpoint this much later than its peers' lag
    scale: StickScale = msgspec.field(default_factory=StickScale)
    envelope: Envelope = msgspec.field(default_factory=lambda: TELLO_ENVELOPE)  # envelope.py

    def __post_init__(self) -> None:
        if isinstance(self.video, bool):
            self.video = "on" if self.video else "off"
        check_ranges(self)
        self.video_policy()  # raises ValueError naming a bad video key
        self.failsafe_config()  # raises ValueError naming a bad timeout or action

    def video_policy(self) -> VideoPolicy:
        """How the video follows its demand, from this config's video keys (validated there)."""
        return VideoPolicy(
            mode=str(self.video),
            idle_s=self.video_idle_s,
            retry_s=self.video_retry_s,
            attempts=self.video_attempts,
        )

    def failsafe_config(self) -> FailsafeConfig:
        """The failsafe's settings, from this config's flat keys (validated there)."""
        return FailsafeConfig(
            setpoint_timeout=self.setpoint_timeout,
            commander_lost_timeout=self.commander_lost_timeout,
            commander_lost_action=self.commander_lost_action,
            keepalive_s=self.keepalive_s,
        )
