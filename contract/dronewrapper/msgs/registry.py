"""The one registry of key expressions and message types. Nothing else spells a key.

Every Zenoh key the system uses is a template here, with the message type carried on it, the
nominal rate and who publishes it. ``{ns}`` is the vehicle namespace (``drone``, ``drone1`` ...).
What a template, a topic and a service are: :mod:`dronewrapper.msgs.keys`.

Size: one table of every key in the system, kept whole so that one file spells them all.

    >>> LOCAL_POSE.key("drone1")
    'drone1/mavros/local_position/pose'
    >>> IMAGE_RAW.key("drone", camera="cam_frontal")
    'drone/cam_frontal/image_raw'
"""

from __future__ import annotations

from typing import Any

from dronewrapper.msgs import (
    control,
    envelope,
    flight,
    geometry,
    lease,
    link,
    mavlink,
    mavros,
    mission,
    refusal,
    sensor,
    simulation,
    std,
    vision,
)
from dronewrapper.msgs.keys import (
    CAMERA_SHORT_NAMES as CAMERA_SHORT_NAMES,
)
from dronewrapper.msgs.keys import (
    CAMERAS as CAMERAS,
)
from dronewrapper.msgs.keys import (
    COMMAND,
    STREAM,
    Liveliness,
    Service,
    Topic,
)
from dronewrapper.msgs.keys import (
    DEFAULT_NAMESPACE as DEFAULT_NAMESPACE,
)
from dronewrapper.msgs.keys import (
    TELEMETRY as TELEMETRY,
)
from dronewrapper.msgs.keys import (
    TRANSPORTS as TRANSPORTS,
)
from dronewrapper.msgs.keys import (
    camera_key_name as camera_key_name,
)

# ---- telemetry (bridge -> everyone) ----
STATE = Topic(
    "{ns}/mavros/state",
    type=mavros.State,
    rate_hz=1.0,
    publishers=("bridge",),
    doc="autopilot state, on change too",
)
EXTENDED_STATE = Topic(
    "{ns}/mavros/extended_state",
    type=mavros.ExtendedState,
    rate_hz=2.0,
    publishers=("bridge",),
    doc="landed state, on change too",
)
LOCAL_POSE = Topic(
    "{ns}/mavros/local_position/pose",
    type=geometry.PoseStamped,
    rate_hz=30.0,
    publishers=("bridge",),
    doc="pose, local ENU",
)
VELOCITY_BODY = Topic(
    "{ns}/mavros/local_position/velocity_body",
    type=geometry.TwistStamped,
    rate_hz=30.0,
    publishers=("bridge",),
    doc="velocity and angular rates, body FLU",
)
VELOCITY_LOCAL = Topic(
    "{ns}/mavros/local_position/velocity_local",
    type=geometry.TwistStamped,
    rate_hz=30.0,
    publishers=("bridge",),
    doc="velocity, local ENU",
)
GLOBAL_POSITION = Topic(
    "{ns}/mavros/global_position/global",
    type=sensor.NavSatFix,
    rate_hz=5.0,
    publishers=("bridge",),
    doc="WGS-84 fix",
)
BATTERY = Topic(
    "{ns}/mavros/battery",
    type=sensor.BatteryState,
    rate_hz=1.0,
    publishers=("bridge",),
    doc="battery, 0..1",
)
LINK_STATUS = Topic(
    "{ns}/bridge/link",
    type=link.LinkStatus,
    rate_hz=1.0,
    publishers=("bridge",),
    doc="the autopilot link's load, losses and reconnects (bridge_mavlink)",
)
STATUSTEXT = Topic(
    "{ns}/mavros/statustext/recv",
    type=mavros.StatusText,
    rate_hz=0.0,
    publishers=("bridge",),
    doc="autopilot text messages",
)

# ---- commands (SDK, controller -> bridge) ----
SETPOINT_RAW_LOCAL = Topic(
    "{ns}/mavros/setpoint_raw/local",
    type=mavros.PositionTarget,
    rate_hz=20.0,
    publishers=("sdk", "controller", "teleop", "ros2_gateway"),
    doc="setpoint, ENU/FLU; re-published at >= 20 Hz while commanding",
    transport=COMMAND,
)

# ---- raw MAVLink for a ground station (bridge_mavlink's gcs_over_zenoh) ----
MAVLINK_FROM_AUTOPILOT = Topic(
    "{ns}/mavlink/from_autopilot",
    type=mavlink.MavlinkFrames,
    rate_hz=0.0,
    publishers=("bridge",),
    doc="the autopilot's MAVLink frames, for a ground station (when enabled)",
)
MAVLINK_TO_AUTOPILOT = Topic(
    "{ns}/mavlink/to_autopilot",
    type=mavlink.MavlinkFrames,
    rate_hz=0.0,
    publishers=("gcs",),
    doc="a ground station's MAVLink frames for the autopilot (when enabled)",
    transport=COMMAND,
)

# ---- cameras and perception ----
IMAGE_RAW = Topic(
    "{ns}/{camera}/image_raw",
    type=sensor.Image,
    rate_hz=30.0,
    publishers=("sim", "camera_victure", "bridge_tello"),
    doc="bgr8",
    transport=STREAM,
)
IMAGE_COMPRESSED = Topic(
    "{ns}/{camera}/image_raw/compressed",
    type=sensor.CompressedImage,
    rate_hz=30.0,
    publishers=("sim", "camera_victure", "bridge_tello"),
    doc="JPEG, on request/config",
    transport=STREAM,
)
CAMERA_INFO = Topic(
    "{ns}/{camera}/camera_info",
    type=sensor.CameraInfo,
    rate_hz=30.0,
    publishers=("camera_victure",),
    doc="intrinsics of the published frames, with each frame (when calibrated)",
)
CAMERA_STATUS = Topic(
    "{ns}/{camera}/camera_status",
    type=sensor.CameraStatus,
    rate_hz=1.0,
    publishers=("camera_victure",),
    doc="camera service state",
)
DETECTIONS = Topic(
    "{ns}/perception/detections",
    type=vision.Detections,
    rate_hz=0.0,
    publishers=("perception",),
    doc="per processed frame",
)
DETECTIONS_DEBUG_IMAGE = Topic(
    "{ns}/perception/debug_image/compressed",
    type=sensor.CompressedImage,
    rate_hz=0.0,
    publishers=("perception",),
    doc="annotated frame for people to watch (optional)",
    transport=STREAM,
)
CONTROLLER_STATUS = Topic(
    "{ns}/controller/status",
    type=control.ControllerStatus,
    rate_hz=5.0,
    publishers=("controller",),
    doc="controller state",
)

# ---- simulator ground truth and world control ----
SIM_GROUND_TRUTH = Topic(
    "{ns}/sim/ground_truth",
    type=geometry.PoseStamped,
    rate_hz=30.0,
    publishers=("sim",),
    doc="true vehicle pose, local ENU",
)
SIM_POSE_SOURCE = Topic(
    "{ns}/sim/pose_source",
    type=simulation.PoseSourceStatus,
    rate_hz=1.0,
    publishers=("sim",),
    doc="where the vehicle pose comes from (an external autopilot's truth) and its age in frames",
)
SIM_OBJECT_POSE = Topic(
    "sim/objects/{name}/pose",
    type=geometry.PoseStamped,
    rate_hz=10.0,
    publishers=("sim",),
    doc="true pose of a world object, ENU",
)
SIM_OBJECT_CMD_VEL = Topic(
    "sim/objects/{name}/cmd_vel",
    type=geometry.Twist,
    rate_hz=0.0,
    publishers=("tests", "teleop"),
    doc="teleoperates an object",
    transport=COMMAND,
)

# ---- replay ----
CLOCK = Topic(
    "clock",
    type=std.Header,
    rate_hz=0.0,
    publishers=("replay",),
    doc="recorded time during a replay (header.stamp, s since the epoch), like ROS /clock",
)

# ---- services ----
ARMING = Service(
    "{ns}/mavros/cmd/arming",
    request=mavros.CommandBool,
    reply=mavros.CommandBoolResult,
    server="bridge",
    doc="arm/disarm",
)
TAKEOFF = Service(
    "{ns}/mavros/cmd/takeoff",
    request=mavros.CommandTOL,
    reply=mavros.CommandTOLResult,
    server="bridge",
    doc="take off",
)
LAND = Service(
    "{ns}/mavros/cmd/land",
    request=mavros.CommandTOL,
    reply=mavros.CommandTOLResult,
    server="bridge",
    doc="land here",
)
SET_MODE = Service(
    "{ns}/mavros/set_mode",
    request=mavros.SetMode,
    reply=mavros.SetModeResult,
    server="bridge",
    doc="change mode",
)
PARAM_GET = Service(
    "{ns}/mavros/param/get",
    request=mavros.ParamGet,
    reply=mavros.ParamGetResult,
    server="bridge",
    doc="read param",
)
PARAM_SET = Service(
    "{ns}/mavros/param/set",
    request=mavros.ParamSet,
    reply=mavros.ParamSetResult,
    server="bridge",
    doc="write param",
)
COMMAND_LEASE = Service(
    "{ns}/dronewrapper/lease",
    request=lease.LeaseRequest,
    reply=lease.LeaseReply,
    server="bridge",
    doc="take or give back the lease",
)
FLIGHT_TAKEOFF = Service(
    "{ns}/dronewrapper/takeoff",
    request=flight.TakeoffRequest,
    reply=flight.FlightResult,
    server="bridge",
    doc="take off to a height; the reply comes once there (or failed)",
)
FLIGHT_LAND = Service(
    "{ns}/dronewrapper/land",
    request=flight.LandRequest,
    reply=flight.FlightResult,
    server="bridge",
    doc="land here; the reply comes once on the ground and disarmed (or failed)",
)
FLIGHT_GOTO = Service(
    "{ns}/dronewrapper/goto",
    request=flight.GotoRequest,
    reply=flight.FlightResult,
    server="bridge",
    doc="fly to a point (ENU m from home, or latitude/longitude) and hold; the reply comes "
    "once there (or failed)",
)
FLIGHT_RETURN = Service(
    "{ns}/dronewrapper/return",
    request=flight.ReturnRequest,
    reply=flight.FlightResult,
    server="bridge",
    doc="fly home and land; the reply comes once on the ground and disarmed (or failed)",
)
FLIGHT_MISSION = Service(
    "{ns}/dronewrapper/mission",
    request=flight.MissionRequest,
    reply=flight.FlightResult,
    server="bridge",
    doc="start, pause or resume the uploaded mission; the reply comes once the aircraft "
    "flies it (or holds)",
)
FLIGHT_CANCEL = Service(
    "{ns}/dronewrapper/cancel",
    request=flight.CancelRequest,
    reply=flight.FlightResult,
    server="bridge",
    doc="end the running take-off, landing, go-to or return at once (its reply: "
    "cancelled); the aircraft holds where it is",
)

# ---- missions, home and the safety envelope (MAVROS's mission/geofence/home keys) ----
MISSION_WAYPOINTS = Topic(
    "{ns}/mavros/mission/waypoints",
    type=mission.WaypointList,
    rate_hz=0.5,
    publishers=("bridge",),
    doc="the mission, on change too",
)
MISSION_REACHED = Topic(
    "{ns}/mavros/mission/reached",
    type=mission.WaypointReached,
    rate_hz=0.0,
    publishers=("bridge",),
    doc="a mission item reached",
)
HOME_POSITION = Topic(
    "{ns}/mavros/home_position/home",
    type=mission.HomePosition,
    rate_hz=0.5,
    publishers=("bridge",),
    doc="home, on change too",
)
COMMANDER_BEAT = Topic(
    "{ns}/dronewrapper/commander/beat",
    type=flight.CommanderBeat,
    rate_hz=1.0,
    publishers=("sdk", "teleop"),
    doc="a commander's process is alive (while its go-to, return or mission may run unattended)",
)
ENVELOPE = Topic(
    "{ns}/dronewrapper/envelope",
    type=envelope.Envelope,
    rate_hz=0.5,
    publishers=("bridge",),
    doc="the safety envelope in force",
)
REFUSAL = Topic(
    "{ns}/dronewrapper/refusal",
    type=refusal.Refusal,
    publishers=("bridge",),
    doc="a setpoint refused or a command overridden, named to its commander (msgs.refusal)",
)
MISSION_PUSH = Service(
    "{ns}/mavros/mission/push",
    request=mission.WaypointPush,
    reply=mission.WaypointPushResult,
    server="bridge",
    doc="upload a mission",
)
MISSION_PULL = Service(
    "{ns}/mavros/mission/pull",
    request=mission.WaypointPull,
    reply=mission.WaypointPullResult,
    server="bridge",
    doc="download it",
)
MISSION_CLEAR = Service(
    "{ns}/mavros/mission/clear",
    request=mission.WaypointClear,
    reply=mission.MissionResult,
    server="bridge",
    doc="clear the mission",
)
MISSION_SET_CURRENT = Service(
    "{ns}/mavros/mission/set_current",
    request=mission.WaypointSetCurrent,
    reply=mission.MissionResult,
    server="bridge",
    doc="fly this item next",
)
MISSION_CONTROL = Service(
    "{ns}/dronewrapper/mission/control",
    request=mission.MissionControl,
    reply=mission.MissionResult,
    server="bridge",
    doc="start, pause or return",
)
GEOFENCE_PUSH = Service(
    "{ns}/mavros/geofence/push",
    request=mission.WaypointClear,
    reply=mission.MissionResult,
    server="bridge",
    doc="upload the envelope's fence to the autopilot",
)
ENVELOPE_SET = Service(
    "{ns}/dronewrapper/envelope/set",
    request=mission.EnvelopeSet,
    reply=mission.EnvelopeResult,
    server="bridge",
    doc="replace or read the safety envelope",
)

SIM_WORLD_LOAD = Service(
    "sim/world/load",
    request=simulation.WorldLoad,
    reply=simulation.WorldState,
    server="sim",
    doc="load a scenario's world, or reset it",
)
SIM_WORLD = Service(
    "sim/world/info",
    request=simulation.WorldQuery,
    reply=simulation.WorldState,
    server="sim",
    doc="the world the sim runs",
)
SIM_RESET = Service(
    "{ns}/sim/world/reset",
    request=simulation.VehicleReset,
    reply=simulation.VehicleResetResult,
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
