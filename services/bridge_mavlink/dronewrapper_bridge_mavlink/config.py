"""bridge_mavlink configuration (strict: an unknown key is an error naming it; see README.md)."""

from __future__ import annotations

import msgspec
from pymavlink.dialects.v20 import common as mavlink

from dronewrapper.envelope import Envelope
from dronewrapper_bridge_base.guided_failsafe import FailsafeConfig
from dronewrapper_bridge_base.unattended import UnattendedConfig
from dronewrapper_bridge_mavlink.gcs import parse_gcs_url
from dronewrapper_bridge_mavlink.keepalive import MAX_PERIOD_S
from dronewrapper_bridge_mavlink.setpoints import Limits
from dronewrapper_bridge_mavlink.streams import message_id

DEFAULT_MESSAGE_RATES = {
    "LOCAL_POSITION_NED": 50.0,
    "ATTITUDE_QUATERNION": 50.0,
    "GLOBAL_POSITION_INT": 10.0,
    "EXTENDED_SYS_STATE": 5.0,
    "SYS_STATUS": 2.0,
    "BATTERY_STATUS": 1.0,
    "GPS_RAW_INT": 2.0,
    "HOME_POSITION": 0.5,
}
UNUSED_STREAMS = ["ALTITUDE", "VFR_HUD", "POSITION_TARGET_LOCAL_NED"]
"""Streams of PX4's onboard link the bridge never reads: asked to stop (see streams.py)."""
SERIAL_UNUSED_STREAMS = [
    "HIGHRES_IMU", "ODOMETRY", "TIMESYNC", "DISTANCE_SENSOR", "ATTITUDE_TARGET",
    "SERVO_OUTPUT_RAW", "NAV_CONTROLLER_OUTPUT", "POSITION_TARGET_GLOBAL_INT", "RC_CHANNELS",
    "ESTIMATOR_STATUS", "VIBRATION", "SCALED_PRESSURE", "WIND_COV", "OPTICAL_FLOW_RAD",
    "OBSTACLE_DISTANCE", "DEBUG", "DEBUG_VECT", "DEBUG_FLOAT_ARRAY", "NAMED_VALUE_FLOAT",
]  # fmt: skip
"""More streams of PX4's onboard mode the bridge never reads, stopped on a serial link only:
PX4 shares its port's data rate (``MAV_x_RATE``, baud / 20 B/s by default) among every stream
it sends, so at 57600 baud HIGHRES_IMU and ODOMETRY left the asked pose at 4.7 Hz."""


class Config(msgspec.Struct, kw_only=True, forbid_unknown_fields=True):
    """bridge_mavlink configuration (units in the names' docs; see README.md)."""

    connection: str = "udpin:127.0.0.1:14540"  # pymavlink URL; loopback unless set otherwise
    baud: int = 57600  # serial only
    link_share: float = 0.6  # serial: share of the line the asked streams may use (link_budget)
    link_warn_load: float = 0.8  # serial: warn when the line is this full (0..1)
    source_system: int = 255  # our MAVLink system id
    source_component: int = 191  # our MAVLink component id (onboard computer; QGC is 190)
    heartbeat_type: int = mavlink.MAV_TYPE_GCS  # our HEARTBEAT's type (GCS: PX4 sends STATUSTEXT)
    target_system: int = 0  # autopilot system id; 0 = the first autopilot heard
    target_component: int = 1
    heartbeat_timeout: float = 3.0  # s without heartbeat -> State.connected false
    stream_rate_hz: float = 30.0  # the stream tick's rate (keep-alive and holds are sent on it)
    setpoint_keepalive_s: float = 0.1  # s: no setpoint sent for this long -> the tick re-sends
    offboard_prime_s: float = 1.2  # s of streaming before asking for OFFBOARD
    final_ack_timeout: float = 1.0  # s to wait for PX4's second (real) DO_SET_MODE ack
    mode_confirm_timeout: float = 2.5  # s for HEARTBEAT to show a mode acked only once
    setpoint_timeout: float = 0.5  # s: velocity commands expire -> hold
    commander_lost_timeout: float = 5.0  # s: no setpoint while airborne -> action
    commander_lost_action: str = "land"  # hold | land | return
    unattended_action: str = "return"  # return | land: a go-to/mission whose commander died
    unattended_lost_timeout: float = 5.0  # s its commander's process may be gone
    command_attempts: int = 5  # sends of a COMMAND_LONG before giving up
    command_ack_timeout: float = 0.6  # s to wait for each COMMAND_ACK
    param_attempts: int = 5
    param_timeout: float = 0.6  # s per PARAM_REQUEST_READ / PARAM_SET attempt
    reason_wait: float = 0.5  # s to wait for a STATUSTEXT explaining a refusal
    state_rate_hz: float = 2.0  # periodic State (also on change)
    extended_state_rate_hz: float = 4.0  # periodic ExtendedState (also on change)
    battery_rate_hz: float = 2.0
    global_position_max_hz: float = 10.0
    message_rates: dict[str, float] = msgspec.field(
        default_factory=lambda: dict(DEFAULT_MESSAGE_RATES)
    )  # Hz asked with SET_MESSAGE_INTERVAL
    unused_streams: list[str] = msgspec.field(
        default_factory=lambda: list(UNUSED_STREAMS)
    )  # messages asked to stop (SET_MESSAGE_INTERVAL -1) unless forwarding to a ground station
    serial_unused_streams: list[str] = msgspec.field(
        default_factory=lambda: list(SERIAL_UNUSED_STREAMS)
    )  # on a serial link, these are asked to stop too (same exception)
    limits: Limits = msgspec.field(default_factory=Limits)
    envelope: Envelope = msgspec.field(default_factory=Envelope)  # where it may fly (envelope.py)
    upload_fence: bool = True  # give the autopilot the envelope as its fence once home is known
    command_lease: bool = (
        False  # obey one commander at a time (dronewrapper_bridge_base.commander_lease)
    )
    command_lease_ttl_s: float = 10.0  # s: a silent holder loses the lease
    late_setpoint_s: float = 0.3  # s: refuse a setpoint this much later than its peers' lag
    signing_key_file: str = ""  # MAVLink 2 signing key (dronewrapper keys mavlink); "" = off
    gcs_url: str = ""  # udp:HOST:PORT of a ground station (QGC 14550) to forward MAVLink to
    gcs_over_zenoh: bool = False  # also forward on {ns}/mavlink/* (dronewrapper mavlink-forward)

    def __post_init__(self) -> None:
        if self.baud <= 0:
            raise ValueError(f"baud must be > 0, got {self.baud!r}")
        for name in ("link_share", "link_warn_load"):
            if not 0 < getattr(self, name) <= 1:
                raise ValueError(f"{name} must be in (0, 1], got {getattr(self, name)!r}")
        if not 0 < self.late_setpoint_s <= 5:
            raise ValueError(f"late_setpoint_s must be in (0, 5] s, got {self.late_setpoint_s!r}")
        self.failsafe_config()  # raises ValueError naming a bad timeout or action
        self.unattended_config()
        if not 0 < self.setpoint_keepalive_s <= MAX_PERIOD_S:
            raise ValueError(
                f"setpoint_keepalive_s must be in (0, {MAX_PERIOD_S}] s, "
                f"got {self.setpoint_keepalive_s!r}"
            )
        if self.stream_rate_hz < 20.0:
            raise ValueError(f"stream_rate_hz must be >= 20 (contract), got {self.stream_rate_hz}")
        for name in ("state_rate_hz", "extended_state_rate_hz", "battery_rate_hz"):
            if not getattr(self, name) > 0:
                raise ValueError(f"{name} must be > 0")
        if self.command_attempts < 1 or self.param_attempts < 1:
            raise ValueError("command_attempts and param_attempts must be >= 1")
        if self.gcs_url:
            parse_gcs_url(self.gcs_url)  # raises ValueError naming the expected form
        for key in ("unused_streams", "serial_unused_streams"):
            for name in getattr(self, key):
                if message_id(name) is None:
                    raise ValueError(f"{key}: {name!r} is not a MAVLink message name")
        for name in ("final_ack_timeout", "mode_confirm_timeout"):
            if not 0 < getattr(self, name) <= 30:
                raise ValueError(f"{name} must be in (0, 30] s, got {getattr(self, name)!r}")

    def unattended_config(self) -> UnattendedConfig:
        """The unattended-action rule's settings (validated there)."""
        return UnattendedConfig(
            lost_timeout=self.unattended_lost_timeout, action=self.unattended_action
        )

    def failsafe_config(self) -> FailsafeConfig:
        """The failsafe's settings, from this config's flat keys (validated there)."""
        return FailsafeConfig(
            setpoint_timeout=self.setpoint_timeout,
            commander_lost_timeout=self.commander_lost_timeout,
            commander_lost_action=self.commander_lost_action,
        )
