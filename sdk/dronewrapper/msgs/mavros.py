"""Vehicle messages and service types shaped like mavros_msgs, with MAVROS/MAVLink constants.

Frames and units follow MAVROS: local ENU, body FLU, SI units, radians. Bridges convert to what
the aircraft speaks (NED/FRD for MAVLink); no user sees NED.
"""

from __future__ import annotations

import math

import msgspec

from dronewrapper.msgs.geometry import Point, Vector3
from dronewrapper.msgs.std import Header

# mavros_msgs/ExtendedState.landed_state (= MAV_LANDED_STATE)
LANDED_STATE_UNDEFINED = 0
LANDED_STATE_ON_GROUND = 1
LANDED_STATE_IN_AIR = 2
LANDED_STATE_TAKEOFF = 3
LANDED_STATE_LANDING = 4

# mavros_msgs/ExtendedState.vtol_state (= MAV_VTOL_STATE)
VTOL_STATE_UNDEFINED = 0
VTOL_STATE_MC = 3

# mavros_msgs/PositionTarget.coordinate_frame (= MAV_FRAME as MAVROS names them)
FRAME_LOCAL_NED = 1
FRAME_LOCAL_OFFSET_NED = 7
FRAME_BODY_NED = 8
FRAME_BODY_OFFSET_NED = 9

# mavros_msgs/PositionTarget.type_mask bits: a set bit means "ignore this field".
IGNORE_PX = 1
IGNORE_PY = 2
IGNORE_PZ = 4
IGNORE_VX = 8
IGNORE_VY = 16
IGNORE_VZ = 32
IGNORE_AFX = 64
IGNORE_AFY = 128
IGNORE_AFZ = 256
FORCE = 512
IGNORE_YAW = 1024
IGNORE_YAW_RATE = 2048

# The DroneWrapper controls (docs/design.md "PositionTarget semantics").
MASK_POSITION = 3064  # x, y, z (local ENU m), yaw (rad)
MASK_VELOCITY = 1991  # vx, vy, vz (body FLU m/s), yaw_rate (rad/s)
MASK_MIXED = 1987  # vx, vy (body FLU m/s), z (local ENU altitude m), yaw_rate (rad/s)

# MAV_RESULT values carried in command replies.
MAV_RESULT_ACCEPTED = 0
MAV_RESULT_TEMPORARILY_REJECTED = 1
MAV_RESULT_DENIED = 2
MAV_RESULT_UNSUPPORTED = 3
MAV_RESULT_FAILED = 4
MAV_RESULT_IN_PROGRESS = 5
MAV_RESULT_CANCELLED = 6
# Not a MAVLink value: no acknowledgement arrived within the bridge's retries.
RESULT_NO_ACK = -1

# MAV_SEVERITY for StatusText.
SEVERITY_EMERGENCY = 0
SEVERITY_ALERT = 1
SEVERITY_CRITICAL = 2
SEVERITY_ERROR = 3
SEVERITY_WARNING = 4
SEVERITY_NOTICE = 5
SEVERITY_INFO = 6
SEVERITY_DEBUG = 7


class State(msgspec.Struct, kw_only=True):
    """Autopilot state (mavros_msgs/State).

    Attributes:
        connected: a heartbeat arrived within the last 3 s.
        armed: motors armed.
        guided: the autopilot accepts external setpoints in this mode (OFFBOARD, GUIDED).
        manual_input: a pilot's sticks drive this mode.
        mode: the mode name as MAVROS spells it (``OFFBOARD``, ``AUTO.LAND``, ``GUIDED`` ...).
        system_status: MAV_STATE (0 unknown ... 4 active).
        autopilot: ``px4``, ``ardupilotmega``, ``tello``, ``sim`` or ``""`` before the first
            heartbeat (an extension of mavros_msgs/State).
        failsafe: the bridge's failsafe state (``""`` none, ``hold``, ``land``, ``return``),
            an extension so every failsafe transition is visible on this key.
    """

    header: Header = msgspec.field(default_factory=Header)
    connected: bool = False
    armed: bool = False
    guided: bool = False
    manual_input: bool = False
    mode: str = ""
    system_status: int = 0
    autopilot: str = ""
    failsafe: str = ""


class ExtendedState(msgspec.Struct, kw_only=True):
    """Extended state (mavros_msgs/ExtendedState); ``landed_state`` is a LANDED_STATE_* value."""

    header: Header = msgspec.field(default_factory=Header)
    vtol_state: int = VTOL_STATE_UNDEFINED
    landed_state: int = LANDED_STATE_UNDEFINED


class PositionTarget(msgspec.Struct, kw_only=True):
    """A setpoint (mavros_msgs/PositionTarget) in the DroneWrapper's ENU/FLU conventions.

    ``coordinate_frame`` is FRAME_LOCAL_NED (1) for local targets and FRAME_BODY_NED (8) for
    body velocities, as MAVROS names them; the values themselves are ENU (local) and FLU (body),
    like MAVROS's topic side. ``type_mask`` bits set = field ignored (MASK_* constants).
    ``header.stamp`` is the stamp of the data that caused the command (a camera frame's stamp
    for vision control), so latency can be measured end to end.
    """

    header: Header = msgspec.field(default_factory=Header)
    coordinate_frame: int = FRAME_LOCAL_NED
    type_mask: int = MASK_POSITION
    position: Point = msgspec.field(default_factory=Point)
    velocity: Vector3 = msgspec.field(default_factory=Vector3)
    acceleration_or_force: Vector3 = msgspec.field(default_factory=Vector3)
    yaw: float = 0.0
    yaw_rate: float = 0.0


class StatusText(msgspec.Struct, kw_only=True):
    """A text message from the autopilot (mavros_msgs/StatusText); severity is MAV_SEVERITY."""

    header: Header = msgspec.field(default_factory=Header)
    severity: int = SEVERITY_INFO
    text: str = ""


class ParamValue(msgspec.Struct, kw_only=True):
    """A parameter value (mavros_msgs/ParamValue): ``integer`` for integers, else ``real``."""

    integer: int = 0
    real: float = 0.0

    def as_number(self) -> int | float:
        """The value as a Python number: the integer when non-zero, else the real."""
        return self.integer if self.integer != 0 else self.real

    @classmethod
    def of(cls, value: int | float) -> ParamValue:
        """Wrap a Python number (bools and ints as integer, floats as real)."""
        if isinstance(value, bool | int):
            return cls(integer=int(value))
        if not math.isfinite(float(value)):
            raise ValueError(f"parameter value must be finite, got {value!r}")
        return cls(real=float(value))


# ---- services (request -> reply), as mavros_msgs/srv, with the autopilot's reason added ----


class CommandBool(msgspec.Struct, kw_only=True):
    """Arming request (mavros_msgs/CommandBool): ``value`` True arms, False disarms."""

    value: bool = True


class CommandBoolResult(msgspec.Struct, kw_only=True):
    """Arming reply: ``success`` iff the autopilot accepted; ``result`` is MAV_RESULT."""

    success: bool = False
    result: int = RESULT_NO_ACK
    message: str = ""


class CommandTOL(msgspec.Struct, kw_only=True):
    """Take-off / land request (mavros_msgs/CommandTOL).

    ``altitude`` is the height above the take-off point in metres for take-off (NaN: the
    autopilot's default); latitude/longitude in degrees, NaN for "here" (works without GPS);
    ``yaw`` in radians ENU, NaN to keep the current heading.
    """

    min_pitch: float = 0.0
    yaw: float = float("nan")
    latitude: float = float("nan")
    longitude: float = float("nan")
    altitude: float = float("nan")


class CommandTOLResult(msgspec.Struct, kw_only=True):
    """Take-off / land reply: ``success`` iff accepted; ``result`` is MAV_RESULT."""

    success: bool = False
    result: int = RESULT_NO_ACK
    message: str = ""


class SetMode(msgspec.Struct, kw_only=True):
    """Mode request (mavros_msgs/SetMode): ``custom_mode`` is a mode name (``OFFBOARD``,
    ``AUTO.LOITER``, ``AUTO.LAND``, ``POSCTL``, ``GUIDED``, ``LAND`` ...)."""

    base_mode: int = 0
    custom_mode: str = ""


class SetModeResult(msgspec.Struct, kw_only=True):
    """Mode reply: ``mode_sent`` iff the autopilot acknowledged the change as accepted."""

    mode_sent: bool = False
    result: int = RESULT_NO_ACK
    message: str = ""


class ParamGet(msgspec.Struct, kw_only=True):
    """Parameter read request (mavros_msgs/ParamGet)."""

    param_id: str = ""


class ParamGetResult(msgspec.Struct, kw_only=True):
    """Parameter read reply."""

    success: bool = False
    value: ParamValue = msgspec.field(default_factory=ParamValue)
    message: str = ""


class ParamSet(msgspec.Struct, kw_only=True):
    """Parameter write request (mavros_msgs/ParamSet)."""

    param_id: str = ""
    value: ParamValue = msgspec.field(default_factory=ParamValue)


class ParamSetResult(msgspec.Struct, kw_only=True):
    """Parameter write reply: ``value`` is what the autopilot reports after the write."""

    success: bool = False
    value: ParamValue = msgspec.field(default_factory=ParamValue)
    message: str = ""
