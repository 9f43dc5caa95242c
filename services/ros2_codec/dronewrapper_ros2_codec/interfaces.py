"""The ROS 2 interfaces our keys map to, as ``.msg``/``.srv`` text, and their parsed fields.

The definitions are those of ROS 2 Jazzy (builtin_interfaces, std_msgs, geometry_msgs,
sensor_msgs) and MAVROS 2 (mavros_msgs 2.x), fields only: constants and comments do not change
the wire format or the type hash. Everything else (hashes, CDR, bag schemas) is derived from
this text.

    >>> [f.name for f in message("builtin_interfaces/msg/Time").fields]
    ['sec', 'nanosec']
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from functools import cache

MESSAGES: dict[str, str] = {
    "builtin_interfaces/msg/Time": "int32 sec\nuint32 nanosec\n",
    "std_msgs/msg/Header": "builtin_interfaces/Time stamp\nstring frame_id\n",
    "geometry_msgs/msg/Point": "float64 x\nfloat64 y\nfloat64 z\n",
    "geometry_msgs/msg/Vector3": "float64 x\nfloat64 y\nfloat64 z\n",
    "geometry_msgs/msg/Quaternion": "float64 x 0\nfloat64 y 0\nfloat64 z 0\nfloat64 w 1\n",
    "geometry_msgs/msg/Pose": "Point position\nQuaternion orientation\n",
    "geometry_msgs/msg/PoseStamped": "std_msgs/Header header\nPose pose\n",
    "geometry_msgs/msg/Twist": "Vector3 linear\nVector3 angular\n",
    "geometry_msgs/msg/TwistStamped": "std_msgs/Header header\nTwist twist\n",
    "sensor_msgs/msg/NavSatStatus": "int8 status\nuint16 service\n",
    "sensor_msgs/msg/NavSatFix": (
        "std_msgs/Header header\nNavSatStatus status\nfloat64 latitude\nfloat64 longitude\n"
        "float64 altitude\nfloat64[9] position_covariance\nuint8 position_covariance_type\n"
    ),
    "sensor_msgs/msg/BatteryState": (
        "std_msgs/Header header\nfloat32 voltage\nfloat32 temperature\nfloat32 current\n"
        "float32 charge\nfloat32 capacity\nfloat32 design_capacity\nfloat32 percentage\n"
        "uint8 power_supply_status\nuint8 power_supply_health\nuint8 power_supply_technology\n"
        "bool present\nfloat32[] cell_voltage\nfloat32[] cell_temperature\nstring location\n"
        "string serial_number\n"
    ),
    "sensor_msgs/msg/Image": (
        "std_msgs/Header header\nuint32 height\nuint32 width\nstring encoding\n"
        "uint8 is_bigendian\nuint32 step\nuint8[] data\n"
    ),
    "sensor_msgs/msg/CompressedImage": "std_msgs/Header header\nstring format\nuint8[] data\n",
    "mavros_msgs/msg/State": (
        "std_msgs/Header header\nbool connected\nbool armed\nbool guided\nbool manual_input\n"
        "string mode\nuint8 system_status\n"
    ),
    "mavros_msgs/msg/ExtendedState": (
        "std_msgs/Header header\nuint8 vtol_state\nuint8 landed_state\n"
    ),
    "mavros_msgs/msg/PositionTarget": (
        "std_msgs/Header header\nuint8 coordinate_frame\nuint16 type_mask\n"
        "geometry_msgs/Point position\ngeometry_msgs/Vector3 velocity\n"
        "geometry_msgs/Vector3 acceleration_or_force\nfloat32 yaw\nfloat32 yaw_rate\n"
    ),
    "mavros_msgs/msg/ParamValue": "int64 integer\nfloat64 real\n",
    # services' Event messages refer to this one (rosidl adds it to every service)
    "service_msgs/msg/ServiceEventInfo": (
        "uint8 event_type\nbuiltin_interfaces/Time stamp\nchar[16] client_gid\n"
        "int64 sequence_number\n"
    ),
}

SERVICES: dict[str, tuple[str, str]] = {
    "mavros_msgs/srv/CommandBool": ("bool value\n", "bool success\nuint8 result\n"),
    "mavros_msgs/srv/CommandTOL": (
        "float32 min_pitch\nfloat32 yaw\nfloat32 latitude\nfloat32 longitude\nfloat32 altitude\n",
        "bool success\nuint8 result\n",
    ),
    "mavros_msgs/srv/SetMode": ("uint8 base_mode\nstring custom_mode\n", "bool mode_sent\n"),
    "mavros_msgs/srv/ParamGet": ("string param_id\n", "bool success\nParamValue value\n"),
    "mavros_msgs/srv/ParamSet": (
        "string param_id\nParamValue value\n",
        "bool success\nParamValue value\n",
    ),
}

PRIMITIVES = (
    "bool",
    "byte",
    "char",
    "int8",
    "uint8",
    "int16",
    "uint16",
    "int32",
    "uint32",
    "int64",
    "uint64",
    "float32",
    "float64",
    "string",
)

SCALAR, ARRAY, SEQUENCE, BOUNDED = "scalar", "array", "sequence", "bounded"

_CONSTANT = re.compile(r"\S+\s+\w+\s*=")
"""A constant line: ``TYPE NAME=VALUE`` (not part of the wire format or the hash)."""
_FIELD = re.compile(
    r"(?P<type>[A-Za-z][\w/]*)(?P<strcap><=\d+)?(?:\[(?P<bound><=)?(?P<size>\d*)\])?"
    r"\s+(?P<name>[a-z]\w*)(?:\s+(?P<default>.+))?\Z"
)


@dataclass(frozen=True)
class Field:
    """One field: its name, base type (a primitive or ``pkg/msg/Name``), how many of it
    (``scalar``, fixed ``array``, unbounded ``sequence`` or ``bounded`` sequence, with
    ``size``), and the bound of a bounded string (0: unbounded)."""

    name: str
    base: str
    kind: str = SCALAR
    size: int = 0
    string_capacity: int = 0

    @property
    def nested(self) -> bool:
        return self.base not in PRIMITIVES


@dataclass(frozen=True)
class Message:
    """A message type: its full name (``pkg/msg/Name``) and fields in order."""

    name: str
    fields: tuple[Field, ...]

    @property
    def package(self) -> str:
        return self.name.split("/")[0]


def _qualify(base: str, package: str) -> str:
    if base in PRIMITIVES:
        return base
    parts = base.split("/")
    if len(parts) == 1:
        return f"{package}/msg/{base}"
    if len(parts) == 2:
        return f"{parts[0]}/msg/{parts[1]}"
    return base


def parse(name: str, text: str) -> Message:
    """Parse ``.msg`` text (constants and comments skipped) into the message ``name``.

    Raises:
        ValueError: a line is not a field or a constant (the message names it).
    """
    package = name.split("/")[0]
    fields = []
    for raw in text.splitlines():
        line = raw.split("#", 1)[0].strip()
        if not line:
            continue
        if _CONSTANT.match(line):
            continue
        match = _FIELD.match(line)
        if match is None:
            raise ValueError(f"{name}: cannot parse {raw!r}")
        base = match["type"]
        kind, size = SCALAR, 0
        if match["size"] is not None or match["bound"]:
            if match["bound"]:
                kind, size = BOUNDED, int(match["size"])
            elif match["size"]:
                kind, size = ARRAY, int(match["size"])
            else:
                kind = SEQUENCE
        strcap = int(match["strcap"][2:]) if match["strcap"] else 0
        fields.append(Field(match["name"], _qualify(base, package), kind, size, strcap))
    return Message(name, tuple(fields))


EMPTY_MEMBER = Field("structure_needs_at_least_one_member", "uint8")
"""The member rosidl gives a message with no fields (IDL structures need one)."""


def service_messages(service: str) -> dict[str, Message]:
    """The messages rosidl makes of service ``pkg/srv/Name``: ``Name_Request``,
    ``Name_Response`` and ``Name_Event``."""
    request_text, response_text = SERVICES[service]
    request = parse(f"{service}_Request", request_text)
    response = parse(f"{service}_Response", response_text)
    request = Message(request.name, request.fields or (EMPTY_MEMBER,))
    response = Message(response.name, response.fields or (EMPTY_MEMBER,))
    event = Message(
        f"{service}_Event",
        (
            Field("info", "service_msgs/msg/ServiceEventInfo"),
            Field("request", request.name, BOUNDED, 1),
            Field("response", response.name, BOUNDED, 1),
        ),
    )
    return {m.name: m for m in (request, response, event)}


def define(messages: dict[str, str]) -> None:
    """Add message types (full name -> ``.msg`` text) to :data:`MESSAGES`, e.g. a firmware's
    own package. Defining a name again with the same text is allowed.

    Raises:
        ValueError: a name is already defined with other text, or a text does not parse.
    """
    for name, text in messages.items():
        known = MESSAGES.get(name)
        if known is not None and known != text:
            raise ValueError(f"{name} is already defined with other fields")
        parse(name, text)
    MESSAGES.update(messages)


@cache
def message(name: str) -> Message:
    """A message type by full name (``sensor_msgs/msg/Image``), or a service's part
    (``mavros_msgs/srv/CommandBool_Request``).

    Raises:
        KeyError: the type is not defined here.
    """
    if name in MESSAGES:
        return parse(name, MESSAGES[name])
    service = name.rsplit("_", 1)[0]
    if "/srv/" in name and service in SERVICES:
        return service_messages(service)[name]
    raise KeyError(f"no ROS 2 interface {name!r} in dronewrapper_ros2_codec.interfaces")


def dependencies(name: str) -> list[str]:
    """Every type ``name`` refers to, directly or not, sorted by name."""
    seen: set[str] = set()
    queue = [f.base for f in message(name).fields if f.nested]
    while queue:
        current = queue.pop()
        if current in seen:
            continue
        seen.add(current)
        queue.extend(f.base for f in message(current).fields if f.nested)
    return sorted(seen)


def dds_type_name(name: str) -> str:
    """The DDS-mangled type name rmw_zenoh puts in keys: ``pkg::msg::dds_::Name_``.

    >>> dds_type_name("mavros_msgs/msg/State")
    'mavros_msgs::msg::dds_::State_'
    """
    package, kind, short = name.split("/")
    return f"{package}::{kind}::dds_::{short}_"


def msg_text(name: str) -> str:
    """The ``ros2msg`` schema text of a message for MCAP: its own definition, then each
    dependency after a ``====`` line and ``MSG: pkg/Name`` (the rosbag2 / Foxglove form)."""
    parts = [_definition_text(name)]
    for dep in dependencies(name):
        package, _, short = dep.split("/")
        parts.append("=" * 80 + f"\nMSG: {package}/{short}\n" + _definition_text(dep))
    return "\n".join(parts)


def _definition_text(name: str) -> str:
    out = []
    for f in message(name).fields:
        base = f.base
        if f.nested:
            package, _, short = base.split("/")
            base = f"{package}/{short}"
        if f.string_capacity:
            base += f"<={f.string_capacity}"
        suffix = {SCALAR: "", ARRAY: f"[{f.size}]", SEQUENCE: "[]", BOUNDED: f"[<={f.size}]"}
        out.append(f"{base}{suffix[f.kind]} {f.name}")
    return "\n".join(out) + "\n"
