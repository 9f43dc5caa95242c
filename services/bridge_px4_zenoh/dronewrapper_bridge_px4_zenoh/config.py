"""bridge_px4_zenoh configuration: a strict schema (an unknown key is refused by name, a bad
value with its key named). Units are in each key's comment; see the package's README.md."""

from __future__ import annotations

from typing import Annotated

import msgspec

from dronewrapper.envelope import Envelope
from dronewrapper.runtime.config_ranges import NonNegative, Positive, check_ranges
from dronewrapper_bridge_base.config_ranges import (
    Attempts,
    ComponentId,
    LateSetpoint,
    Seconds60,
    StreamRate,
)
from dronewrapper_bridge_base.guided_failsafe import FailsafeConfig
from dronewrapper_bridge_base.setpoint_limits import Limits
from dronewrapper_bridge_base.unattended import UnattendedConfig


class Config(msgspec.Struct, kw_only=True, forbid_unknown_fields=True):
    """bridge_px4_zenoh configuration (see module docstring)."""

    # PX4's ZENOH_DOMAIN_ID (a ROS 2 domain): the first chunk of its keys
    domain: Annotated[int, msgspec.Meta(ge=0, le=232)] = 0
    target_system: ComponentId = 0  # PX4's MAV_SYS_ID (instance N: N + 1); 0 = vehicle_status's
    target_component: ComponentId = 0  # PX4's component id; 0 = vehicle_status's
    link_timeout: Seconds60 = 1.0  # s without a sample from PX4 -> State.connected false
    stream_rate_hz: StreamRate = 30.0  # own setpoint stream rate while commanded
    offboard_prime_s: Seconds60 = 1.2  # s of streaming before asking for OFFBOARD
    mode_confirm_timeout: Seconds60 = 2.5  # s for vehicle_status to show an accepted mode
    setpoint_timeout: float = 0.5  # s: velocity commands expire -> hold
    commander_lost_timeout: float = 5.0  # s: no setpoint while airborne -> action
    commander_lost_action: str = "land"  # hold | land | return
    unattended_action: str = "return"  # return | land: a go-to whose commander's process died
    unattended_lost_timeout: float = 5.0  # s its commander's process may be gone
    command_attempts: Attempts = 3  # sends of a vehicle command before giving up
    command_ack_timeout: Seconds60 = 0.5  # s to wait for each vehicle_command_ack
    state_rate_hz: Positive = 2.0  # periodic State (also on change)
    extended_state_rate_hz: Positive = 4.0  # periodic ExtendedState (also on change)
    battery_rate_hz: Positive = 2.0
    pose_max_hz: NonNegative = 0.0  # cap on pose and velocity samples; 0: one a tick (stream rate)
    global_position_max_hz: NonNegative = 10.0
    limits: Limits = msgspec.field(default_factory=Limits)  # bounds on accepted setpoints
    envelope: Envelope = msgspec.field(default_factory=Envelope)  # where it may fly
    command_lease: bool = False  # obey one commander at a time (bridge_base.commander_lease)
    command_lease_ttl_s: Seconds60 = 10.0  # s: a silent holder loses the lease
    late_setpoint_s: LateSetpoint = 0.3  # s: refuse a setpoint this much later than its peers' lag

    def __post_init__(self) -> None:
        check_ranges(self)
        self.failsafe_config()  # raises ValueError naming a bad timeout or action
        self.unattended_config()

    def failsafe_config(self) -> FailsafeConfig:
        """The failsafe's settings, from this config's flat keys (validated there)."""
        return FailsafeConfig(
            setpoint_timeout=self.setpoint_timeout,
            commander_lost_timeout=self.commander_lost_timeout,
            commander_lost_action=self.commander_lost_action,
        )

    def unattended_config(self) -> UnattendedConfig:
        """The unattended-action rule's settings (validated there)."""
        return UnattendedConfig(
            lost_timeout=self.unattended_lost_timeout, action=self.unattended_action
        )
