"""bridge_mavlink configuration (strict: an unknown key is an error naming it; see README.md)."""

from __future__ import annotations

from typing import Annotated

import msgspec
from pymavlink.dialects.v20 import common as mavlink

from dronewrapper.envelope import Envelope
from dronewrapper.runtime.config_ranges import Positive, check_ranges
from dronewrapper_bridge_base.config_ranges import (
    Attempts,
    LateSetpoint,
    Seconds30,
    StreamRate,
)
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

LinkShare = Annotated[float, msgspec.Meta(gt=0, le=1)]
"""A share of a serial line's data rate, in (0, 1]."""
KeepalivePeriod = Annotated[float, msgspec.Meta(gt=0, le=MAX_PERIOD_S)]
"""How long without a setpoint sent before the tick re-sends one (s; PX4 drops OFFBOARD after
0.5 s)."""


class Config(msgspec.Struct, kw_only=True, forbid_unknown_fields=True):
    """bridge_mavlink configuration (units in the names' docs; see README.md)."""

    connection: str = "udpin:127.0.0.1:14540"  # pymavlink URL; loopback unless set otherwise
    baud: Annotated[int, msgspec.Meta(gt=0)] = 57600  # serial only
    link_share: LinkShare = 0.6  # serial: the line's share the asked streams may use (link_budget)
    link_warn_load: LinkShare = 0.8  # serial: warn when the line is this full (0..1)
    source_system: int = 255  # our MAVLink system id
    source_component: int = 191  # our MAVLink component id (onboard computer; QGC is 190)
    heartbeat_type: int = mavlink.MAV_TYPE_GCS  # our HEARTBEAT's type (GCS: PX4 sends STATUSTEXT)
    target_system: int = 0  # autopilot system id; 0 = the first autopilot heard
    target_component: int = 1
    heartbeat_timeout: float = 3.0  # s without heartbeat -> State.connected false
    stream_rate_hz: StreamRate = 30.0  # the stream tick's rate (keep-alives and holds go on it)
    setpoint_keepalive_s: KeepalivePeriod = 0.1  # s: none sent for this long -> the tick re-sends
    offboard_prime_s: float = 1.2  # s of streaming before asking for OFFBOARD
    final_ack_timeout: Seconds30 = 1.0  # s to wait for PX4's second (real) DO_SET_MODE ack
    mode_confirm_timeout: Seconds30 = 2.5  # s for HEARTBEAT to show a mode acked only once
    setpoint_timeout: float = 0.5  # s: velocity commands expire -> hold
    commander_lost_timeout: float = 5.0  # s: no setpoint while airborne -> action
    commander_lost_action: str = "land"  # hold | land | return
    unattended_action: str = "return"  # return | land: a go-to/mission whose commander died
    unattended_lost_timeout: float = 5.0  # s its commander's process may be gone
    command_attempts: Attempts = 5  # sends of a COMMAND_LONG before giving up
    command_ack_timeout: float = 0.6  # s to wait for each COMMAND_ACK
    param_attempts: Attempts = 5
    param_timeout: float = 0.6  # s per PARAM_REQUEST_READ / PARAM_SET attempt
    reason_wait: float = 0.5  # s to wait for a STATUSTEXT explaining a refusal
    state_rate_hz: Positive = 2.0  # periodic State (also on change)
    extended_state_rate_hz: Positive = 4.0  # periodic ExtendedState (also on change)
    battery_rate_hz: Positive = 2.0
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
    late_setpoint_s: LateSetpoint = 0.3  # s: refuse a setpoint this much later than its peers' lag
    signing_key_file: str = ""  # MAVLink 2 signing key (dronewrapper keys mavlink); "" = off
    gcs_url: str = ""  # udp:HOST:PORT of a ground station (QGC 14550) to forward MAVLink to
    gcs_over_zenoh: bool = False  # also forward on {ns}/mavlink/* (dronewrapper mavlink-forward)

    def __post_init__(self) -> None:
        check_ranges(self)
        self.failsafe_config()  # raises ValueError naming a bad timeout or action
        self.unattended_config()
        if self.gcs_url:
            parse_gcs_url(self.gcs_url)  # raises ValueError naming the expected form
        for key in ("unused_streams", "serial_unused_streams"):
            for name in getattr(self, key):
                if message_id(name) is None:
                    raise ValueError(f"{key}: {name!r} is not a MAVLink message name")

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
