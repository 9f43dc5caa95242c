"""The MAVLink messages the bridge sends, as typed immutable values (:data:`Send`), and the one
encoder that makes pymavlink's message of each (:func:`encode`).

The core, its operations and the mission transfers queue these values in the
:class:`Outbox`; only
the link (``link.MavLink.send``) encodes them, so no message name travels as a string and the
type checker sees every field. Units are MAVLink's: ``time_boot_ms`` ms since the bridge's
start, positions local NED m, velocities m/s, yaw rad, rates rad/s; mission ``x``/``y``
degrees * 1e7 and ``z`` m. ``target_system``/``target_component`` address the autopilot.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, NoReturn, Protocol

from pymavlink.dialects.v20 import common as mavlink

from dronewrapper.msgs.registry import Topic
from dronewrapper_bridge_base.core_view import Clock
from dronewrapper_bridge_mavlink.setpoints import LocalNedTarget


@dataclass(frozen=True, slots=True)
class Heartbeat:
    """HEARTBEAT: the bridge's own (MAV_TYPE, MAV_AUTOPILOT, modes, MAV_STATE)."""

    type: int
    autopilot: int
    base_mode: int
    custom_mode: int
    system_status: int


@dataclass(frozen=True, slots=True)
class Addressed:
    """What every message but HEARTBEAT starts with: the autopilot's (system, component)."""

    target_system: int
    target_component: int


@dataclass(frozen=True, slots=True)
class CommandLong(Addressed):
    """COMMAND_LONG: MAV_CMD ``command`` with its seven parameters (``confirmation``: 0 on the
    first send, counted up on each re-send)."""

    command: int
    confirmation: int
    params: tuple[float, float, float, float, float, float, float]


@dataclass(frozen=True, slots=True)
class SetPositionTargetLocalNed(Addressed):
    """SET_POSITION_TARGET_LOCAL_NED: ``target`` (:class:`~.setpoints.LocalNedTarget`, what
    the autopilot is asked for; no acceleration is ever sent) at ``time_boot_ms``."""

    time_boot_ms: int
    target: LocalNedTarget


@dataclass(frozen=True, slots=True)
class ParamRequestRead(Addressed):
    """PARAM_REQUEST_READ of ``param_id`` (ASCII, <= 16 bytes; ``param_index`` -1: by id)."""

    param_id: bytes
    param_index: int = -1


@dataclass(frozen=True, slots=True)
class ParamSet(Addressed):
    """PARAM_SET: ``param_value`` as it travels (PX4 integers as their bytes), MAV_PARAM_TYPE."""

    param_id: bytes
    param_value: float
    param_type: int


@dataclass(frozen=True, slots=True)
class MissionRequestList(Addressed):
    """MISSION_REQUEST_LIST: a download of the autopilot's list of ``mission_type`` begins
    (the autopilot answers with MISSION_COUNT)."""

    mission_type: int


@dataclass(frozen=True, slots=True)
class MissionCount(Addressed):
    """MISSION_COUNT: an upload of ``count`` items of MAV_MISSION_TYPE ``mission_type``
    begins; the autopilot then asks for each item (MISSION_REQUEST_INT)."""

    count: int
    mission_type: int


@dataclass(frozen=True, slots=True)
class MissionItemInt(Addressed):
    """MISSION_ITEM_INT: item ``seq`` (MAV_FRAME ``frame``, MAV_CMD ``command``; ``x``, ``y``
    degrees times 1e7, ``z`` m)."""

    seq: int
    frame: int
    command: int
    current: int
    autocontinue: int
    param1: float
    param2: float
    param3: float
    param4: float
    x: int
    y: int
    z: float
    mission_type: int


@dataclass(frozen=True, slots=True)
class MissionAck(Addressed):
    """MISSION_ACK: a download's end (``type``: MAV_MISSION_RESULT)."""

    type: int
    mission_type: int


@dataclass(frozen=True, slots=True)
class MissionClearAll(Addressed):
    """MISSION_CLEAR_ALL of ``mission_type``."""

    mission_type: int


@dataclass(frozen=True, slots=True)
class MissionRequestInt(Addressed):
    """MISSION_REQUEST_INT: item ``seq`` of a download."""

    seq: int
    mission_type: int


Send = (
    Heartbeat
    | CommandLong
    | SetPositionTargetLocalNed
    | ParamRequestRead
    | ParamSet
    | MissionCount
    | MissionItemInt
    | MissionRequestList
    | MissionRequestInt
    | MissionClearAll
    | MissionAck
)
"""Every message the bridge's core sends to the autopilot."""


class AutopilotPort(Clock, Protocol):
    """The core as a part of it that talks to the autopilot sees it: its time (``now``,
    monotonic s, set by each entry point), the autopilot's (system, component), the outbox."""

    def target(self) -> tuple[int, int]: ...
    def send(self, message: Send) -> None: ...


@dataclass
class Outbox:
    """What the node must do after a core call.

    Attributes:
        sends: MAVLink messages for the autopilot, typed (the link encodes them).
        samples: (registry topic, message) to publish on Zenoh.
        peers: UDP addresses replies must go to from now on (the last one wins).
        errors: names of dropped inputs to count (the node's ``callback_errors``).
    """

    sends: list[Send] = field(default_factory=list)
    samples: list[tuple[Topic, Any]] = field(default_factory=list)
    peers: list[Any] = field(default_factory=list)
    errors: list[str] = field(default_factory=list)


def encode(send: Send) -> mavlink.MAVLink_message:
    """pymavlink's message for ``send`` (packed and sent by ``MAVLink.send``)."""
    if isinstance(send, SetPositionTargetLocalNed):  # the most frequent first
        s = send.target
        return mavlink.MAVLink_set_position_target_local_ned_message(
            send.time_boot_ms,
            send.target_system,
            send.target_component,
            s.coordinate_frame,
            s.type_mask,
            s.x,
            s.y,
            s.z,
            s.vx,
            s.vy,
            s.vz,
            0.0,  # afx, afy, afz: no acceleration
            0.0,
            0.0,
            s.yaw,
            s.yaw_rate,
        )
    if isinstance(send, Heartbeat):
        return mavlink.MAVLink_heartbeat_message(
            send.type, send.autopilot, send.base_mode, send.custom_mode, send.system_status, 3
        )
    if isinstance(send, CommandLong):
        return mavlink.MAVLink_command_long_message(
            send.target_system, send.target_component, send.command, send.confirmation, *send.params
        )
    if isinstance(send, ParamRequestRead):
        return mavlink.MAVLink_param_request_read_message(
            send.target_system, send.target_component, send.param_id, send.param_index
        )
    if isinstance(send, ParamSet):
        return mavlink.MAVLink_param_set_message(
            send.target_system,
            send.target_component,
            send.param_id,
            send.param_value,
            send.param_type,
        )
    if isinstance(send, MISSION_MESSAGES):
        return _encode_mission(send)
    return _unknown(send)


MissionMessage = (
    MissionCount
    | MissionItemInt
    | MissionRequestList
    | MissionRequestInt
    | MissionClearAll
    | MissionAck
)
"""The mission protocol's messages (mission_transfer.py sends them)."""
MISSION_MESSAGES = (
    MissionCount,
    MissionItemInt,
    MissionRequestList,
    MissionRequestInt,
    MissionClearAll,
    MissionAck,
)


def _encode_mission(send: MissionMessage) -> mavlink.MAVLink_message:
    target = (send.target_system, send.target_component)
    if isinstance(send, MissionCount):
        return mavlink.MAVLink_mission_count_message(*target, send.count, send.mission_type)
    if isinstance(send, MissionItemInt):
        s = send
        return mavlink.MAVLink_mission_item_int_message(
            *target,
            s.seq,
            s.frame,
            s.command,
            s.current,
            s.autocontinue,
            s.param1,
            s.param2,
            s.param3,
            s.param4,
            s.x,
            s.y,
            s.z,
            s.mission_type,
        )
    if isinstance(send, MissionRequestList):
        return mavlink.MAVLink_mission_request_list_message(*target, send.mission_type)
    if isinstance(send, MissionRequestInt):
        return mavlink.MAVLink_mission_request_int_message(*target, send.seq, send.mission_type)
    if isinstance(send, MissionClearAll):
        return mavlink.MAVLink_mission_clear_all_message(*target, send.mission_type)
    if isinstance(send, MissionAck):
        return mavlink.MAVLink_mission_ack_message(*target, send.type, send.mission_type)
    return _unknown(send)


def _unknown(send: NoReturn) -> NoReturn:
    """Reached only by a value outside :data:`Send` (the type checker proves none is)."""
    raise TypeError(f"not a message the bridge sends: {send!r}")


__all__ = [
    "Addressed",
    "AutopilotPort",
    "CommandLong",
    "Heartbeat",
    "MissionAck",
    "MissionClearAll",
    "MissionCount",
    "MissionItemInt",
    "MissionRequestInt",
    "MissionRequestList",
    "ParamRequestRead",
    "ParamSet",
    "Send",
    "SetPositionTargetLocalNed",
    "encode",
]
