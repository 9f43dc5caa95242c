"""Vehicle messages and service types shaped like mavros_msgs, with MAVROS/MAVLink constants.

Frames and units follow MAVROS: local ENU, body FLU, SI units, radians. Bridges convert to what
the aircraft speaks (NED/FRD for MAVLink); no user sees NED.

The MAVLink values below are MAVROS's message constants, written here because the SDK does not
depend on pymavlink; tests/unit/test_msgs_mavlink_constants.py pins each to pymavlink's.
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


class State(msgspec.Struct, frozen=True, kw_only=True):
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
        commander: who holds the command lease (``""``: nobody, or the lease is off), an
            extension; a take-over shows here at once.
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
    commander: str = ""


class ExtendedState(msgspec.Struct, kw_only=True, frozen=True):
    """Extended state (mavros_msgs/ExtendedState); ``landed_state`` is a LANDED_STATE_* value."""

    header: Header = msgspec.field(default_factory=Header)
    vtol_state: int = VTOL_STATE_UNDEFINED
    landed_state: int = LANDED_STATE_UNDEFINED


class PositionTarget(msgspec.Struct, kw_only=True, frozen=True):
    """A setpoint (mavros_msgs/PositionTarget) in the DroneWrapper's ENU/FLU conventions.

    ``coordinate_frame`` is FRAME_LOCAL_NED (1) for local targets and FRAME_BODY_NED (8) for
    body velocities, as MAVROS names them; the values themselves are ENU (local) and FLU (body),
    like MAVROS's topic side. ``type_mask`` bits set = field ignored (MASK_* constants).
    ``header.stamp`` is the stamp of the data that caused the command (a camera frame's stamp
    for vision control), so latency can be measured end to end. ``coordinate_frame`` and
    ``type_mask`` are required (no default could be safe), and so is ``position`` for the
    position and mixed masks (left out, it is UNSET, never the origin).
    """

    header: Header = msgspec.field(default_factory=Header)
    coordinate_frame: int  # required: an empty message must not mean "go to the origin"
    type_mask: int
    # UNSET when left out: a position or mixed target without it is refused, never "z = 0"
    position: Point | msgspec.UnsetType = msgspec.UNSET
    velocity: Vector3 = msgspec.field(default_factory=Vector3)
    acceleration_or_force: Vector3 = msgspec.field(default_factory=Vector3)
    yaw: float = 0.0
    yaw_rate: float = 0.0

    def required_position(self) -> Point:
        """``position``, which a position or mixed target carries; ValueError when left out."""
        if isinstance(self.position, msgspec.UnsetType):
            raise ValueError(f"position is required with type_mask {self.type_mask}")
        return self.position


class StatusText(msgspec.Struct, kw_only=True, frozen=True):
    """A text message from the autopilot (mavros_msgs/StatusText); severity is MAV_SEVERITY."""

    header: Header = msgspec.field(default_factory=Header)
    severity: int = SEVERITY_INFO
    text: str = ""


PARAM_INTEGER = "integer"
PARAM_REAL = "real"


class ParamValue(msgspec.Struct, kw_only=True, forbid_unknown_fields=True, frozen=True):
    """A parameter value (mavros_msgs/ParamValue): ``integer`` for integers, else ``real``.

    ``kind`` (our addition: ``integer``, ``real``, or empty when unknown) says which field
    holds the value, so an integer parameter equal to 0 is 0, not 0.0.
    """

    integer: int = 0
    real: float = 0.0
    kind: str = ""

    def as_number(self) -> int | float:
        """The value as a Python number: by ``kind`` when set; else (as MAVROS) the integer
        when non-zero, else the real."""
        if self.kind == PARAM_INTEGER:
            return self.integer
        if self.kind == PARAM_REAL:
            return self.real
        return self.integer if self.integer != 0 else self.real

    @classmethod
    def of(cls, value: int | float) -> ParamValue:
        """Wrap a Python number (bools and ints as integer, floats as real)."""
        if isinstance(value, bool | int):
            return cls(integer=int(value), kind=PARAM_INTEGER)
        if not math.isfinite(float(value)):
            raise ValueError(f"parameter value must be finite, got {value!r}")
        return cls(real=float(value), kind=PARAM_REAL)


# ---- services (request -> reply), as mavros_msgs/srv, with the autopilot's reason added ----
#
# Requests are strict (docs/design.md: "bad input changes nothing"): every field that could make the
# aircraft do something has no default, so a request that leaves it out is refused instead of
# acting on a guess (``CommandBool {}`` must never arm); unknown fields are refused with their
# name (a misspelt ``altitude`` must not be silently ignored); values are checked for finiteness
# and range at decode time, so a bad request is answered with an error naming the field before
# any handler runs.


def _check_nan_or_within(owner: str, name: str, value: float, bound: float, unit: str) -> None:
    if not math.isnan(value) and not (math.isfinite(value) and abs(value) <= bound):
        raise ValueError(f"{owner}.{name} must be NaN or within ±{bound:g} {unit}, got {value!r}")


class CommandBool(msgspec.Struct, kw_only=True, forbid_unknown_fields=True, frozen=True):
    """Arming request (mavros_msgs/CommandBool): ``value`` True arms, False disarms (required:
    an empty request arms nothing)."""

    value: bool


class CommandBoolResult(msgspec.Struct, kw_only=True, frozen=True):
    """Arming reply: ``success`` iff the autopilot accepted; ``result`` is MAV_RESULT."""

    success: bool = False
    result: int = RESULT_NO_ACK
    message: str = ""


MAX_TOL_ALTITUDE = 10_000.0  # m: bound on CommandTOL.altitude (services narrow it further)


class CommandTOL(msgspec.Struct, kw_only=True, forbid_unknown_fields=True, frozen=True):
    """Take-off / land request (mavros_msgs/CommandTOL); every field is required.

    ``altitude`` is the height above the take-off point in metres for take-off (NaN: the
    autopilot's default; ignored by land); latitude/longitude in degrees, NaN for "here" (works
    without GPS); ``yaw`` in radians ENU, NaN to keep the current heading; ``min_pitch`` in
    degrees (MAV_CMD_NAV_TAKEOFF param 1, finite, within ±90; 0 for multicopters). Use
    :meth:`takeoff` and :meth:`land` to build one.
    """

    min_pitch: float
    yaw: float
    latitude: float
    longitude: float
    altitude: float

    def __post_init__(self) -> None:
        if not (math.isfinite(self.min_pitch) and abs(self.min_pitch) <= 90.0):
            raise ValueError(
                f"CommandTOL.min_pitch must be finite within ±90 degrees, got {self.min_pitch!r}"
            )
        _check_nan_or_within("CommandTOL", "yaw", self.yaw, 4.0 * math.pi, "rad")
        _check_nan_or_within("CommandTOL", "latitude", self.latitude, 90.0, "degrees")
        _check_nan_or_within("CommandTOL", "longitude", self.longitude, 180.0, "degrees")
        _check_nan_or_within("CommandTOL", "altitude", self.altitude, MAX_TOL_ALTITUDE, "m")

    @classmethod
    def takeoff(cls, altitude: float = math.nan, yaw: float = math.nan) -> CommandTOL:
        """A take-off request: ``altitude`` m above the take-off point, ``yaw`` rad ENU."""
        return cls(min_pitch=0.0, yaw=yaw, latitude=math.nan, longitude=math.nan, altitude=altitude)

    @classmethod
    def land(cls, latitude: float = math.nan, longitude: float = math.nan) -> CommandTOL:
        """A land request at ``latitude``/``longitude`` degrees (NaN: here)."""
        return cls(
            min_pitch=0.0, yaw=math.nan, latitude=latitude, longitude=longitude, altitude=math.nan
        )


class CommandTOLResult(msgspec.Struct, kw_only=True, frozen=True):
    """Take-off / land reply: ``success`` iff accepted; ``result`` is MAV_RESULT."""

    success: bool = False
    result: int = RESULT_NO_ACK
    message: str = ""


class SetMode(msgspec.Struct, kw_only=True, forbid_unknown_fields=True, frozen=True):
    """Mode request (mavros_msgs/SetMode): ``custom_mode`` is a mode name (``OFFBOARD``,
    ``AUTO.LOITER``, ``AUTO.LAND``, ``POSCTL``, ``GUIDED``, ``LAND`` ...), required;
    ``base_mode`` must be 0 (MAVROS's "use custom_mode"; the bridge sets the base mode)."""

    base_mode: int = 0
    custom_mode: str

    def __post_init__(self) -> None:
        if self.base_mode != 0:
            raise ValueError(f"SetMode.base_mode must be 0 (use custom_mode), got {self.base_mode}")
        if not self.custom_mode or len(self.custom_mode) > 64:
            raise ValueError(
                f"SetMode.custom_mode must be a mode name of 1-64 characters, "
                f"got {self.custom_mode[:80]!r}"
            )


class SetModeResult(msgspec.Struct, kw_only=True, frozen=True):
    """Mode reply: ``mode_sent`` iff the autopilot acknowledged the change as accepted."""

    mode_sent: bool = False
    result: int = RESULT_NO_ACK
    message: str = ""


class ParamGet(msgspec.Struct, kw_only=True, forbid_unknown_fields=True, frozen=True):
    """Parameter read request (mavros_msgs/ParamGet); ``param_id`` is required."""

    param_id: str


class ParamGetResult(msgspec.Struct, kw_only=True, frozen=True):
    """Parameter read reply."""

    success: bool = False
    value: ParamValue = msgspec.field(default_factory=ParamValue)
    message: str = ""


class ParamSet(msgspec.Struct, kw_only=True, forbid_unknown_fields=True, frozen=True):
    """Parameter write request (mavros_msgs/ParamSet); both fields are required (an empty
    ``value`` would write 0). ``value.real`` must be finite; the bridge checks the range
    against the parameter's type (float32, int32)."""

    param_id: str
    value: ParamValue

    def __post_init__(self) -> None:
        if not math.isfinite(self.value.real):
            raise ValueError(f"ParamSet.value.real must be finite, got {self.value.real!r}")

    @classmethod
    def of(cls, param_id: str, value: int | float) -> ParamSet:
        """The request that writes ``value`` (wrapped by :meth:`ParamValue.of`) to ``param_id``."""
        return cls(param_id=param_id, value=ParamValue.of(value))


class ParamSetResult(msgspec.Struct, kw_only=True, frozen=True):
    """Parameter write reply: ``value`` is what the autopilot reports after the write."""

    success: bool = False
    value: ParamValue = msgspec.field(default_factory=ParamValue)
    message: str = ""
