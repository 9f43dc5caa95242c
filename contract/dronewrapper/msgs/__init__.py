"""Message types and key expressions of DroneWrapper: the contract every process imports.

Messages are msgspec Structs shaped like the ROS messages MAVROS uses, encoded as MessagePack
maps. Keys live in :mod:`dronewrapper.msgs.registry`; nothing else spells a key.
"""

from dronewrapper.msgs.codec import DecodeError, decode, decoder, encode, schema_name, to_builtins
from dronewrapper.msgs.control import ControllerStatus
from dronewrapper.msgs.geometry import (
    Point,
    Pose,
    PoseStamped,
    Quaternion,
    Twist,
    TwistStamped,
    Vector3,
)
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
    ParamValue,
    PositionTarget,
    SetMode,
    SetModeResult,
    State,
    StatusText,
)
from dronewrapper.msgs.sensor import (
    BatteryState,
    CameraInfo,
    CameraStatus,
    CompressedImage,
    Image,
    NavSatFix,
    NavSatStatus,
)
from dronewrapper.msgs.std import ErrorReply, Header
from dronewrapper.msgs.vision import (
    BoundingBox2D,
    Detection2D,
    Detections,
    ObjectHypothesis,
    ObjectHypothesisWithPose,
    Point2D,
    Pose2D,
)

__all__ = [
    "BatteryState",
    "BoundingBox2D",
    "CameraInfo",
    "CameraStatus",
    "CommandBool",
    "CommandBoolResult",
    "CommandTOL",
    "CommandTOLResult",
    "CompressedImage",
    "ControllerStatus",
    "DecodeError",
    "Detection2D",
    "Detections",
    "ErrorReply",
    "ExtendedState",
    "Header",
    "Image",
    "NavSatFix",
    "NavSatStatus",
    "ObjectHypothesis",
    "ObjectHypothesisWithPose",
    "ParamGet",
    "ParamGetResult",
    "ParamSet",
    "ParamSetResult",
    "ParamValue",
    "Point",
    "Point2D",
    "Pose",
    "Pose2D",
    "PoseStamped",
    "PositionTarget",
    "Quaternion",
    "SetMode",
    "SetModeResult",
    "State",
    "StatusText",
    "Twist",
    "TwistStamped",
    "Vector3",
    "decode",
    "decoder",
    "encode",
    "schema_name",
    "to_builtins",
]
