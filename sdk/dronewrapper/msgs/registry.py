"""The one registry of key expressions and message types. Nothing else spells a key.

Every Zenoh key the system uses is a template here, with the message type carried on it, the
nominal rate and who publishes it. ``{ns}`` is the vehicle namespace (``drone``, ``drone1`` ...).

    >>> LOCAL_POSE.key("drone1")
    'drone1/mavros/local_position/pose'
    >>> IMAGE_RAW.key("drone", camera="cam_frontal")
    'drone/cam_frontal/image_raw'
"""

from __future__ import annotations

import re
import string
from dataclasses import KW_ONLY, dataclass, field
from functools import cached_property
from typing import Any, Generic, TypeVar

from dronewrapper.msgs.control import ControllerStatus
from dronewrapper.msgs.envelope import Envelope
from dronewrapper.msgs.flight import (
    CancelRequest,
    CommanderBeat,
    FlightResult,
    GotoRequest,
    LandRequest,
    MissionRequest,
    ReturnRequest,
    TakeoffRequest,
)
from dronewrapper.msgs.geometry import PoseStamped, Twist, TwistStamped
from dronewrapper.msgs.lease import LeaseReply, LeaseRequest
from dronewrapper.msgs.link import LinkStatus
from dronewrapper.msgs.mavlink import MavlinkFrames
from dronewrapper.msgs.mavros import (
    CommandBool,
    CommandBoolResult,
    CommandTOL,
    CommandTOLResult,
    ExtendedState,
    ParamGet,
    ParamGetResult,
    ParamSet,
    ParamSetResult,
    PositionTarget,
    SetMode,
    SetModeResult,
    State,
    StatusText,
)
from dronewrapper.msgs.mission import (
    EnvelopeResult,
    EnvelopeSet,
    HomePosition,
    MissionControl,
    MissionResult,
    WaypointClear,
    WaypointList,
    WaypointPull,
    WaypointPullResult,
    WaypointPush,
    WaypointPushResult,
    WaypointReached,
    WaypointSetCurrent,
)
from dronewrapper.msgs.refusal import Refusal
from dronewrapper.msgs.sensor import (
    BatteryState,
    CameraInfo,
    CameraStatus,
    CompressedImage,
    Image,
    NavSatFix,
)
from dronewrapper.msgs.simulation import (
    PoseSourceStatus,
    VehicleReset,
    VehicleResetResult,
    WorldLoad,
    WorldQuery,
    WorldState,
)
from dronewrapper.msgs.std import Header
from dronewrapper.msgs.vision import Detections

T = TypeVar("T")
Req = TypeVar("Req")
Rep = TypeVar("Rep")

DEFAULT_NAMESPACE = "drone"
CAMERAS = ("cam_frontal", "cam_ventral")
CAMERA_SHORT_NAMES = {"frontal": "cam_frontal", "ventral": "cam_ventral"}
"""The SDK's camera names (``get_image("frontal")``) and the key names they stand for."""


def camera_key_name(camera: str) -> str:
    """The key name (``cam_frontal``) of a camera given by short or key name.

    Raises:
        ValueError: an unknown camera.
    """
    if camera in CAMERA_SHORT_NAMES:
        return CAMERA_SHORT_NAMES[camera]
    if camera in CAMERAS:
        return camera
    raise ValueError(f"unknown camera {camera!r}: use 'frontal' or 'ventral'")


_FIELD_VALUE = r"[A-Za-z0-9_\-.]+"  # one chunk: no '/', no wildcard


def _fields(template: str) -> tuple[str, ...]:
    return tuple(name for _, name, _, _ in string.Formatter().parse(template) if name)


def _check_chunk(name: str, value: str) -> str:
    if not isinstance(value, str) or not re.fullmatch(_FIELD_VALUE, value):
        raise ValueError(f"key field {name}={value!r} must be one chunk of [A-Za-z0-9_-.]")
    return value


@dataclass(frozen=True)
class _Template:
    template: str

    @cached_property
    def fields(self) -> tuple[str, ...]:
        """Names of the placeholders in the template, in order."""
        return _fields(self.template)

    def key(self, ns: str = DEFAULT_NAMESPACE, **parts: str) -> str:
        """The concrete key for namespace ``ns`` and the other placeholders in ``parts``."""
        values = {"ns": ns, **parts}
        missing = [f for f in self.fields if f not in values]
        if missing:
            raise ValueError(f"{self.template}: missing key field(s) {', '.join(missing)}")
        return self.template.format(**{f: _check_chunk(f, values[f]) for f in self.fields})

    def wildcard(self, ns: str = "*", **parts: str) -> str:
        """A key expression matching every instance (unset placeholders become ``*``)."""
        values = {"ns": ns, **parts}
        return self.template.format(**{f: values.get(f, "*") for f in self.fields})

    @cached_property
    def regex(self) -> re.Pattern[str]:
        """Regex matching concrete keys of this template, capturing each placeholder."""
        out = ""
        for literal, name, _, _ in string.Formatter().parse(self.template):
            out += re.escape(literal)
            if name:
                out += f"(?P<{name}>{_FIELD_VALUE})"
        return re.compile(out + r"\Z")

    def match(self, key: str) -> dict[str, str] | None:
        """The placeholder values if ``key`` is an instance of this template, else None."""
        m = self.regex.match(key)
        return m.groupdict() if m else None


COMMAND = "command"
"""Transport class of commands (setpoints, teleop): highest priority, sent at once, and the
sender waits rather than drop one."""
TELEMETRY = "telemetry"
"""Transport class of telemetry, state and detections: high priority, never behind images; a
publisher is never blocked by a slow subscriber (its queue drops only if the link is dead)."""
STREAM = "stream"
"""Transport class of camera frames: lowest priority, latest-only, dropped under congestion,
so a slow link loses frames but never control."""
TRANSPORTS = (COMMAND, TELEMETRY, STREAM)


@dataclass(frozen=True)
class Topic(_Template, Generic[T]):
    """A pub/sub key: template, message type, nominal rate (Hz, 0 = event-driven), publishers,
    and its transport class (``command``, ``telemetry`` or ``stream``); all but the template are
    keyword entries."""

    _: KW_ONLY
    type: type[T] = field(default=object)  # type: ignore[assignment]
    rate_hz: float = 0.0
    publishers: tuple[str, ...] = ()
    doc: str = ""
    transport: str = TELEMETRY

    def __post_init__(self) -> None:
        if self.transport not in TRANSPORTS:
            raise ValueError(f"{self.template}: transport must be one of {TRANSPORTS}")


@dataclass(frozen=True)
class Service(_Template, Generic[Req, Rep]):
    """A request/reply key served by a Zenoh queryable (keyword entries after the template)."""

    _: KW_ONLY
    request: type[Req] = field(default=object)  # type: ignore[assignment]
    reply: type[Rep] = field(default=object)  # type: ignore[assignment]
    server: str = ""
    doc: str = ""


@dataclass(frozen=True)
class Liveliness(_Template):
    """A liveliness token key: present while the process holding it is alive."""

    _: KW_ONLY
    doc: str = ""


# ---- telemetry (bridge -> everyone) ----
STATE = Topic(
    "{ns}/mavros/state",
    type=State,
    rate_hz=1.0,
    publishers=("bridge",),
    doc="autopilot state, on change too",
)
EXTENDED_STATE = Topic(
    "{ns}/mavros/extended_state",
    type=ExtendedState,
    rate_hz=2.0,
    publishers=("bridge",),
    doc="landed state, on change too",
)
LOCAL_POSE = Topic(
    "{ns}/mavros/local_position/pose",
    type=PoseStamped,
    rate_hz=30.0,
    publishers=("bridge",),
    doc="pose, local ENU",
)
VELOCITY_BODY = Topic(
    "{ns}/mavros/local_position/velocity_body",
    type=TwistStamped,
    rate_hz=30.0,
    publishers=("bridge",),
    doc="velocity and angular rates, body FLU",
)
VELOCITY_LOCAL = Topic(
    "{ns}/mavros/local_position/velocity_local",
    type=TwistStamped,
    rate_hz=30.0,
    publishers=("bridge",),
    doc="velocity, local ENU",
)
GLOBAL_POSITION = Topic(
    "{ns}/mavros/global_position/global",
    type=NavSatFix,
    rate_hz=5.0,
    publishers=("bridge",),
    doc="WGS-84 fix",
)
BATTERY = Topic(
    "{ns}/mavros/battery",
    type=BatteryState,
    rate_hz=1.0,
    publishers=("bridge",),
    doc="battery, 0..1",
)
LINK_STATUS = Topic(
    "{ns}/bridge/link",
    type=LinkStatus,
    rate_hz=1.0,
    publishers=("bridge",),
    doc="the autopilot link's load, losses and reconnects (bridge_mavlink)",
)
STATUSTEXT = Topic(
    "{ns}/mavros/statustext/recv",
    type=StatusText,
    rate_hz=0.0,
    publishers=("bridge",),
    doc="autopilot text messages",
)

# ---- commands (SDK, controller -> bridge) ----
SETPOINT_RAW_LOCAL = Topic(
    "{ns}/mavros/setpoint_raw/local",
    type=PositionTarget,
    rate_hz=20.0,
    publishers=("sdk", "controller"),
    doc="setpoint, ENU/FLU; re-published at >= 20 Hz while commanding",
    transport=COMMAND,
)

# ---- raw MAVLink for a ground station (bridge_mavlink's gcs_over_zenoh) ----
MAVLINK_FROM_AUTOPILOT = Topic(
    "{ns}/mavlink/from_autopilot",
    type=MavlinkFrames,
    rate_hz=0.0,
    publishers=("bridge",),
    doc="the autopilot's MAVLink frames, for a ground station (when enabled)",
)
MAVLINK_TO_AUTOPILOT = Topic(
    "{ns}/mavlink/to_autopilot",
    type=MavlinkFrames,
    rate_hz=0.0,
    publishers=("gcs",),
    doc="a ground station's MAVLink frames for the autopilot (when enabled)",
    transport=COMMAND,
)

# ---- cameras and perception ----
IMAGE_RAW = Topic(
    "{ns}/{camera}/image_raw",
    type=Image,
    rate_hz=30.0,
    publishers=("sim", "camera_victure", "bridge_tello"),
    doc="bgr8",
    transport=STREAM,
)
IMAGE_COMPRESSED = Topic(
    "{ns}/{camera}/image_raw/compressed",
    type=CompressedImage,
    rate_hz=30.0,
    publishers=("sim", "camera_victure", "bridge_tello"),
    doc="JPEG, on request/config",
    transport=STREAM,
)
CAMERA_INFO = Topic(
    "{ns}/{camera}/camera_info",
    type=CameraInfo,
    rate_hz=30.0,
    publishers=("camera_victure",),
    doc="intrinsics of the published frames, with each frame (when calibrated)",
)
CAMERA_STATUS = Topic(
    "{ns}/{camera}/camera_status",
    type=CameraStatus,
    rate_hz=1.0,
    publishers=("camera_victure",),
    doc="camera service state",
)
DETECTIONS = Topic(
    "{ns}/perception/detections",
    type=Detections,
    rate_hz=0.0,
    publishers=("perception",),
    doc="per processed frame",
)
DETECTIONS_DEBUG_IMAGE = Topic(
    "{ns}/perception/debug_image/compressed",
    type=CompressedImage,
    rate_hz=0.0,
    publishers=("perception",),
    doc="annotated frame for people to watch (optional)",
    transport=STREAM,
)
CONTROLLER_STATUS = Topic(
    "{ns}/controller/status",
    type=ControllerStatus,
    rate_hz=5.0,
    publishers=("controller",),
    doc="controller state",
)

# ---- simulator ground truth and world control ----
SIM_GROUND_TRUTH = Topic(
    "{ns}/sim/ground_truth",
    type=PoseStamped,
    rate_hz=30.0,
    publishers=("sim",),
    doc="true vehicle pose, local ENU",
)
SIM_POSE_SOURCE = Topic(
    "{ns}/sim/pose_source",
    type=PoseSourceStatus,
    rate_hz=1.0,
    publishers=("sim",),
    doc="where the vehicle pose comes from (an external autopilot's truth) and its age in frames",
)
SIM_OBJECT_POSE = Topic(
    "sim/objects/{name}/pose",
    type=PoseStamped,
    rate_hz=10.0,
    publishers=("sim",),
    doc="true pose of a world object, ENU",
)
SIM_OBJECT_CMD_VEL = Topic(
    "sim/objects/{name}/cmd_vel",
    type=Twist,
    rate_hz=0.0,
    publishers=("tests", "teleop"),
    doc="teleoperates an object",
    transport=COMMAND,
)

# ---- replay ----
CLOCK = Topic(
    "clock",
    type=Header,
    rate_hz=0.0,
    publishers=("replay",),
    doc="recorded time during a replay (header.stamp, s since the epoch), like ROS /clock",
)

# ---- services ----
ARMING = Service(
    "{ns}/mavros/cmd/arming",
    request=CommandBool,
    reply=CommandBoolResult,
    server="bridge",
    doc="arm/disarm",
)
TAKEOFF = Service(
    "{ns}/mavros/cmd/takeoff",
    request=CommandTOL,
    reply=CommandTOLResult,
    server="bridge",
    doc="take off",
)
LAND = Service(
    "{ns}/mavros/cmd/land",
    request=CommandTOL,
    reply=CommandTOLResult,
    server="bridge",
    doc="land here",
)
SET_MODE = Service(
    "{ns}/mavros/set_mode", request=SetMode, reply=SetModeResult, server="bridge", doc="change mode"
)
PARAM_GET = Service(
    "{ns}/mavros/param/get",
    request=ParamGet,
    reply=ParamGetResult,
    server="bridge",
    doc="read param",
)
PARAM_SET = Service(
    "{ns}/mavros/param/set",
    request=ParamSet,
    reply=ParamSetResult,
    server="bridge",
    doc="write param",
)
COMMAND_LEASE = Service(
    "{ns}/dronewrapper/lease",
    request=LeaseRequest,
    reply=LeaseReply,
    server="bridge",
    doc="take or give back the lease",
)
FLIGHT_TAKEOFF = Service(
    "{ns}/dronewrapper/takeoff",
    request=TakeoffRequest,
    reply=FlightResult,
    server="bridge",
    doc="take off to a height; the reply comes once there (or failed)",
)
FLIGHT_LAND = Service(
    "{ns}/dronewrapper/land",
    request=LandRequest,
    reply=FlightResult,
    server="bridge",
    doc="land here; the reply comes once on the ground and disarmed (or failed)",
)
FLIGHT_GOTO = Service(
    "{ns}/dronewrapper/goto",
    request=GotoRequest,
    reply=FlightResult,
    server="bridge",
    doc="fly to a point (ENU m from home, or latitude/longitude) and hold; the reply comes "
    "once there (or failed)",
)
FLIGHT_RETURN = Service(
    "{ns}/dronewrapper/return",
    request=ReturnRequest,
    reply=FlightResult,
    server="bridge",
    doc="fly home and land; the reply comes once on the ground and disarmed (or failed)",
)
FLIGHT_MISSION = Service(
    "{ns}/dronewrapper/mission",
    request=MissionRequest,
    reply=FlightResult,
    server="bridge",
    doc="start, pause or resume the uploaded mission; the reply comes once the aircraft "
    "flies it (or holds)",
)
FLIGHT_CANCEL = Service(
    "{ns}/dronewrapper/cancel",
    request=CancelRequest,
    reply=FlightResult,
    server="bridge",
    doc="end the running take-off, landing, go-to or return at once (its reply: "
    "cancelled); the aircraft holds where it is",
)

# ---- missions, home and the safety envelope (MAVROS's mission/geofence/home keys) ----
MISSION_WAYPOINTS = Topic(
    "{ns}/mavros/mission/waypoints",
    type=WaypointList,
    rate_hz=0.5,
    publishers=("bridge",),
    doc="the mission, on change too",
)
MISSION_REACHED = Topic(
    "{ns}/mavros/mission/reached",
    type=WaypointReached,
    rate_hz=0.0,
    publishers=("bridge",),
    doc="a mission item reached",
)
HOME_POSITION = Topic(
    "{ns}/mavros/home_position/home",
    type=HomePosition,
    rate_hz=0.5,
    publishers=("bridge",),
    doc="home, on change too",
)
COMMANDER_BEAT = Topic(
    "{ns}/dronewrapper/commander/beat",
    type=CommanderBeat,
    rate_hz=1.0,
    publishers=("sdk",),
    doc="a commander's process is alive (while its go-to, return or mission may run unattended)",
)
ENVELOPE = Topic(
    "{ns}/dronewrapper/envelope",
    type=Envelope,
    rate_hz=0.5,
    publishers=("bridge",),
    doc="the safety envelope in force",
)
REFUSAL = Topic(
    "{ns}/dronewrapper/refusal",
    type=Refusal,
    publishers=("bridge",),
    doc="a setpoint refused or a command overridden, named to its commander (msgs.refusal)",
)
MISSION_PUSH = Service(
    "{ns}/mavros/mission/push",
    request=WaypointPush,
    reply=WaypointPushResult,
    server="bridge",
    doc="upload a mission",
)
MISSION_PULL = Service(
    "{ns}/mavros/mission/pull",
    request=WaypointPull,
    reply=WaypointPullResult,
    server="bridge",
    doc="download it",
)
MISSION_CLEAR = Service(
    "{ns}/mavros/mission/clear",
    request=WaypointClear,
    reply=MissionResult,
    server="bridge",
    doc="clear the mission",
)
MISSION_SET_CURRENT = Service(
    "{ns}/mavros/mission/set_current",
    request=WaypointSetCurrent,
    reply=MissionResult,
    server="bridge",
    doc="fly this item next",
)
MISSION_CONTROL = Service(
    "{ns}/dronewrapper/mission/control",
    request=MissionControl,
    reply=MissionResult,
    server="bridge",
    doc="start, pause or return",
)
GEOFENCE_PUSH = Service(
    "{ns}/mavros/geofence/push",
    request=WaypointClear,
    reply=MissionResult,
    server="bridge",
    doc="upload the envelope's fence to the autopilot",
)
ENVELOPE_SET = Service(
    "{ns}/dronewrapper/envelope/set",
    request=EnvelopeSet,
    reply=EnvelopeResult,
    server="bridge",
    doc="replace or read the safety envelope",
)

SIM_WORLD_LOAD = Service(
    "sim/world/load",
    request=WorldLoad,
    reply=WorldState,
    server="sim",
    doc="load a scenario's world, or reset it",
)
SIM_WORLD = Service(
    "sim/world/info",
    request=WorldQuery,
    reply=WorldState,
    server="sim",
    doc="the world the sim runs",
)
SIM_RESET = Service(
    "{ns}/sim/world/reset",
    request=VehicleReset,
    reply=VehicleResetResult,
    server="sim",
    doc="put this simulated vehicle back at its start pose, on the ground, motors off",
)

# ---- liveliness ----
ALIVE = Liveliness("{ns}/alive/{service}", doc="held by every running service")


def _collect(kind: type) -> dict[str, Any]:
    return {name: obj for name, obj in globals().items() if isinstance(obj, kind)}


TOPICS: dict[str, Topic[Any]] = _collect(Topic)
SERVICES: dict[str, Service[Any, Any]] = _collect(Service)
LIVELINESS: dict[str, Liveliness] = _collect(Liveliness)


def topic_for_key(key: str) -> Topic[Any] | None:
    """The registered topic a concrete key belongs to, or None if the key is unknown."""
    for topic in TOPICS.values():
        if topic.match(key) is not None:
            return topic
    return None


def service_for_key(key: str) -> Service[Any, Any] | None:
    """The registered service a concrete key belongs to, or None."""
    for service in SERVICES.values():
        if service.match(key) is not None:
            return service
    return None
