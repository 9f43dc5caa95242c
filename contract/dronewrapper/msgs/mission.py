"""Missions, home and the safety envelope, shaped like mavros_msgs (Waypoint, WaypointPush ...).

A :class:`Waypoint` is a MAVLink mission item as MAVROS carries it: ``x_lat``/``y_long`` in
degrees (WGS-84), ``z_alt`` in metres above home for FRAME_GLOBAL_REL_ALT (3). The safety
envelope (:class:`dronewrapper.envelope.Envelope`) travels as it is; its positions are ENU m
in the home frame.
"""

from __future__ import annotations

import math

import msgspec

from dronewrapper.msgs.envelope import Envelope
from dronewrapper.msgs.std import Header

# MAV_FRAME values a mission item takes.
FRAME_GLOBAL = 0
FRAME_MISSION = 2
FRAME_GLOBAL_REL_ALT = 3
FRAME_GLOBAL_RELATIVE_ALT_INT = 6

MAX_PARAM = 1e7  # |param1..4| (s, m, deg ...): beyond is a mistake, and float32 ends at 3e38

# MAV_CMD values of mission items.
NAV_WAYPOINT = 16
NAV_RETURN_TO_LAUNCH = 20
NAV_LAND = 21
NAV_TAKEOFF = 22
NAV_RALLY_POINT = 5100  # a place a return may fly to instead of home (MAV_MISSION_TYPE_RALLY)
MAX_RALLY_POINTS = 100

COMMAND_NAMES = {  # MAV_CMD names (without MAV_CMD_) of the items mission plans hold
    16: "NAV_WAYPOINT",
    17: "NAV_LOITER_UNLIM",
    18: "NAV_LOITER_TURNS",
    19: "NAV_LOITER_TIME",
    20: "NAV_RETURN_TO_LAUNCH",
    21: "NAV_LAND",
    22: "NAV_TAKEOFF",
    31: "NAV_LOITER_TO_ALT",
    82: "NAV_SPLINE_WAYPOINT",
    84: "NAV_VTOL_TAKEOFF",
    85: "NAV_VTOL_LAND",
    93: "NAV_DELAY",
    112: "CONDITION_DELAY",
    177: "DO_JUMP",
    178: "DO_CHANGE_SPEED",
    179: "DO_SET_HOME",
    183: "DO_SET_SERVO",
    189: "DO_LAND_START",
    195: "DO_SET_ROI_LOCATION",
    196: "DO_SET_ROI_WPNEXT_OFFSET",
    197: "DO_SET_ROI_NONE",
    201: "DO_SET_ROI",
    202: "DO_DIGICAM_CONFIGURE",
    203: "DO_DIGICAM_CONTROL",
    204: "DO_MOUNT_CONFIGURE",
    205: "DO_MOUNT_CONTROL",
    206: "DO_SET_CAM_TRIGG_DIST",
    211: "DO_GRIPPER",
    214: "DO_SET_CAM_TRIGG_INTERVAL",
    530: "SET_CAMERA_MODE",
    531: "SET_CAMERA_ZOOM",
    532: "SET_CAMERA_FOCUS",
    1000: "DO_GIMBAL_MANAGER_PITCHYAW",
    2000: "IMAGE_START_CAPTURE",
    2001: "IMAGE_STOP_CAPTURE",
    2500: "VIDEO_START_CAPTURE",
    2501: "VIDEO_STOP_CAPTURE",
    5100: "NAV_RALLY_POINT",
}


def command_name(command: int) -> str:
    """The MAV_CMD name of ``command`` (``NAV_WAYPOINT``), or ``MAV_CMD 1234``."""
    return COMMAND_NAMES.get(command, f"MAV_CMD {command}")


class Waypoint(msgspec.Struct, kw_only=True, forbid_unknown_fields=True, frozen=True):
    """One mission item (mavros_msgs/Waypoint): degrees, metres above home, MAV_CMD params.
    ``x_lat``, ``y_long`` and ``z_alt`` are required: no default place is safe to fly to."""

    x_lat: float
    y_long: float
    z_alt: float

    frame: int = FRAME_GLOBAL_REL_ALT
    command: int = NAV_WAYPOINT
    is_current: bool = False
    autocontinue: bool = True
    param1: float = 0.0  # NAV_WAYPOINT: hold time (s)
    param2: float = 0.0  # NAV_WAYPOINT: acceptance radius (m)
    param3: float = 0.0
    param4: float = math.nan  # NAV_WAYPOINT: yaw (deg), NaN: the autopilot's choice

    def __post_init__(self) -> None:
        if not (math.isfinite(self.x_lat) and abs(self.x_lat) <= 90):
            raise ValueError(f"waypoint x_lat must be within ±90 degrees, got {self.x_lat!r}")
        if not (math.isfinite(self.y_long) and abs(self.y_long) <= 180):
            raise ValueError(f"waypoint y_long must be within ±180 degrees, got {self.y_long!r}")
        if not (math.isfinite(self.z_alt) and -1000 <= self.z_alt <= 10_000):
            raise ValueError(f"waypoint z_alt must be within [-1000, 10000] m, got {self.z_alt!r}")
        for name in ("param1", "param2", "param3", "param4"):
            value = getattr(self, name)
            if not (math.isfinite(value) and abs(value) <= MAX_PARAM) and not (
                name == "param4" and math.isnan(value)
            ):
                raise ValueError(f"waypoint {name} must be within ±{MAX_PARAM:g}, got {value!r}")
        if not 0 <= self.command <= 65535 or not 0 <= self.frame <= 255:
            raise ValueError("waypoint command must be a MAV_CMD and frame a MAV_FRAME")


class WaypointList(msgspec.Struct, kw_only=True, frozen=True):
    """The mission the autopilot holds (mavros_msgs/WaypointList); ``current_seq``: the item
    being flown."""

    header: Header = msgspec.field(default_factory=Header)
    current_seq: int = 0
    waypoints: list[Waypoint] = msgspec.field(default_factory=list)


class WaypointReached(msgspec.Struct, kw_only=True, frozen=True):
    """A mission item was reached (mavros_msgs/WaypointReached)."""

    header: Header = msgspec.field(default_factory=Header)
    wp_seq: int = 0


class WaypointPush(msgspec.Struct, kw_only=True, forbid_unknown_fields=True, frozen=True):
    """Upload ``waypoints`` as the new mission (mavros_msgs/WaypointPush; full uploads only).

    ``rally``: the rally points uploaded with it (NAV_RALLY_POINT items, each a position in a
    mission frame; ``[]`` clears the autopilot's), None leaves the autopilot's rally points as
    they are (a mission given as a list of points)."""

    start_index: int = 0
    waypoints: list[Waypoint] = msgspec.field(default_factory=list)
    rally: list[Waypoint] | None = None

    def __post_init__(self) -> None:
        if self.start_index != 0:
            raise ValueError("start_index must be 0: only whole missions are uploaded")
        if len(self.waypoints) > 1000:
            raise ValueError(f"at most 1000 waypoints, got {len(self.waypoints)}")
        rally = self.rally or []
        if len(rally) > MAX_RALLY_POINTS:
            raise ValueError(f"at most {MAX_RALLY_POINTS} rally points, got {len(rally)}")
        for number, point in enumerate(rally):
            if point.command != NAV_RALLY_POINT or point.frame == FRAME_MISSION:
                raise ValueError(
                    f"rally point {number}: a NAV_RALLY_POINT ({NAV_RALLY_POINT}) with a "
                    f"position, got command {point.command} in frame {point.frame}"
                )


class WaypointPushResult(msgspec.Struct, kw_only=True, frozen=True):
    """``wp_transfered``: items the autopilot took (MAVROS's spelling); all of them on success."""

    success: bool = False
    wp_transfered: int = 0
    message: str = ""


class WaypointPull(msgspec.Struct, kw_only=True, forbid_unknown_fields=True, frozen=True):
    """Download the autopilot's mission (mavros_msgs/WaypointPull)."""


class WaypointPullResult(msgspec.Struct, kw_only=True, frozen=True):
    success: bool = False
    wp_received: int = 0
    message: str = ""
    waypoints: list[Waypoint] = msgspec.field(default_factory=list)


class WaypointClear(msgspec.Struct, kw_only=True, forbid_unknown_fields=True, frozen=True):
    """Clear the autopilot's mission (mavros_msgs/WaypointClear)."""


class WaypointSetCurrent(msgspec.Struct, kw_only=True, forbid_unknown_fields=True, frozen=True):
    """Fly item ``wp_seq`` next (mavros_msgs/WaypointSetCurrent)."""

    wp_seq: int = 0

    def __post_init__(self) -> None:
        if isinstance(self.wp_seq, bool) or not 0 <= self.wp_seq < 65535:
            raise ValueError(f"wp_seq must be in [0, 65535), got {self.wp_seq!r}")


class MissionControl(msgspec.Struct, kw_only=True, forbid_unknown_fields=True, frozen=True):
    """``start`` (fly the mission from its current item; resumes after a pause), ``pause``
    (hold where the aircraft is) or ``return`` (fly home and land)."""

    action: str

    def __post_init__(self) -> None:
        if self.action not in ("start", "pause", "return"):
            raise ValueError(f"action must be start, pause or return, got {self.action!r}")


class MissionResult(msgspec.Struct, kw_only=True, frozen=True):
    """The reply of the mission and envelope services: ``success`` and a reason."""

    success: bool = False
    message: str = ""


class EnvelopeSet(msgspec.Struct, kw_only=True, forbid_unknown_fields=True, frozen=True):
    """Replace the bridge's envelope with ``envelope`` (None: only read it); ``reset``: put
    the bridge's configured envelope back instead."""

    envelope: Envelope | None = None
    reset: bool = False


class EnvelopeResult(msgspec.Struct, kw_only=True, frozen=True):
    """The envelope in force after the call; ``set_by``: the commander that set it (``""``:
    it is the bridge's configured one)."""

    success: bool = False
    message: str = ""
    envelope: Envelope = msgspec.field(default_factory=Envelope)
    set_by: str = ""


class HomePosition(msgspec.Struct, kw_only=True, frozen=True):
    """Home (mavros_msgs/HomePosition): geodetic (deg, m AMSL; NaN unknown) and local ENU m."""

    header: Header = msgspec.field(default_factory=Header)
    latitude: float = math.nan
    longitude: float = math.nan
    altitude: float = math.nan
    x: float = 0.0
    y: float = 0.0
    z: float = 0.0


__all__ = [
    "COMMAND_NAMES",
    "FRAME_GLOBAL_REL_ALT",
    "MAX_RALLY_POINTS",
    "NAV_LAND",
    "NAV_RALLY_POINT",
    "NAV_RETURN_TO_LAUNCH",
    "NAV_TAKEOFF",
    "NAV_WAYPOINT",
    "EnvelopeResult",
    "EnvelopeSet",
    "HomePosition",
    "MissionControl",
    "MissionResult",
    "Waypoint",
    "WaypointClear",
    "WaypointList",
    "WaypointPull",
    "WaypointPullResult",
    "WaypointPush",
    "WaypointPushResult",
    "WaypointReached",
    "WaypointSetCurrent",
    "command_name",
]
