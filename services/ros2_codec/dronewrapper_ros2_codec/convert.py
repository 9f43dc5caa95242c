"""Our messages as ROS 2 values (the dicts :mod:`dronewrapper_ros2_codec.cdr` encodes) and back.

Field names are already ROS's; what differs is the header stamp (float seconds since the epoch
here; ``builtin_interfaces/Time`` ``sec``/``nanosec`` in ROS), our extensions (``Header.seq``,
``State.autopilot``/``failsafe``/``commander``, ``ParamValue.kind``), which ROS 2 has no field
for, and unknown battery fields, which ROS writes as NaN. A command reply's ``result`` is a
``uint8`` in ROS: our "no acknowledgement" (-1) becomes MAV_RESULT_FAILED (4).

    >>> time_of(1.5)
    {'sec': 1, 'nanosec': 500000000}
"""

from __future__ import annotations

import math
from typing import Any

import msgspec

from dronewrapper import msgs
from dronewrapper.msgs.mavros import MAV_RESULT_FAILED

ROS_TYPES: dict[type, str] = {
    msgs.State: "mavros_msgs/msg/State",
    msgs.ExtendedState: "mavros_msgs/msg/ExtendedState",
    msgs.PoseStamped: "geometry_msgs/msg/PoseStamped",
    msgs.TwistStamped: "geometry_msgs/msg/TwistStamped",
    msgs.NavSatFix: "sensor_msgs/msg/NavSatFix",
    msgs.BatteryState: "sensor_msgs/msg/BatteryState",
    msgs.Image: "sensor_msgs/msg/Image",
    msgs.CompressedImage: "sensor_msgs/msg/CompressedImage",
    msgs.PositionTarget: "mavros_msgs/msg/PositionTarget",
}
"""Our message type -> the ROS 2 message it is."""

ROS_SERVICES: dict[type, str] = {
    msgs.CommandBool: "mavros_msgs/srv/CommandBool",
    msgs.CommandTOL: "mavros_msgs/srv/CommandTOL",
    msgs.SetMode: "mavros_msgs/srv/SetMode",
    msgs.ParamGet: "mavros_msgs/srv/ParamGet",
    msgs.ParamSet: "mavros_msgs/srv/ParamSet",
}
"""Our request type -> the ROS 2 service it is."""


def time_of(stamp: float) -> dict[str, int]:
    """builtin_interfaces/Time of a float stamp (s since the epoch; negative or non-finite: 0)."""
    if not math.isfinite(stamp) or stamp <= 0:
        return {"sec": 0, "nanosec": 0}
    sec = math.floor(stamp)
    nanosec = round((stamp - sec) * 1e9)
    if nanosec >= 1_000_000_000:
        sec, nanosec = sec + 1, nanosec - 1_000_000_000
    return {"sec": int(sec), "nanosec": int(nanosec)}


def stamp_of(time: dict[str, Any]) -> float:
    """A float stamp (s since the epoch) of a builtin_interfaces/Time value."""
    return float(time["sec"]) + float(time["nanosec"]) * 1e-9


def header_of(header: msgs.Header) -> dict[str, Any]:
    return {"stamp": time_of(header.stamp), "frame_id": header.frame_id}


def _plain(value: Any) -> Any:
    """A Struct as a dict, recursively (headers as ROS headers, buffers left as they are)."""
    if isinstance(value, msgs.Header):
        return header_of(value)
    if isinstance(value, msgspec.Struct):
        return {name: _plain(getattr(value, name)) for name in value.__struct_fields__}
    return value


def to_ros(msg: Any) -> dict[str, Any]:
    """The ROS 2 value of one of our messages (a type in :data:`ROS_TYPES`)."""
    if isinstance(msg, msgs.BatteryState):
        value = _plain(msg)
        value.update(temperature=math.nan, design_capacity=math.nan)
        return value
    if isinstance(msg, msgs.PositionTarget) and msg.position is msgspec.UNSET:
        return _plain(msgspec.structs.replace(msg, position=msgs.Point()))
    return _plain(msg)


def _header(value: dict[str, Any]) -> msgs.Header:
    return msgs.Header(stamp=stamp_of(value["stamp"]), frame_id=value["frame_id"])


def _point(value: dict[str, Any]) -> msgs.Point:
    return msgs.Point(x=value["x"], y=value["y"], z=value["z"])


def _vector(value: dict[str, Any]) -> msgs.Vector3:
    return msgs.Vector3(x=value["x"], y=value["y"], z=value["z"])


def position_target(value: dict[str, Any]) -> msgs.PositionTarget:
    """Our PositionTarget of a decoded mavros_msgs/PositionTarget (values as sent: the
    bridge's rules judge them)."""
    return msgs.PositionTarget(
        header=_header(value["header"]),
        coordinate_frame=value["coordinate_frame"],
        type_mask=value["type_mask"],
        position=_point(value["position"]),
        velocity=_vector(value["velocity"]),
        acceleration_or_force=_vector(value["acceleration_or_force"]),
        yaw=value["yaw"],
        yaw_rate=value["yaw_rate"],
    )


def from_ros(msg_type: type, value: dict[str, Any]) -> Any:
    """One of our messages from its decoded ROS 2 value (the inverse of :func:`to_ros` where
    ROS has the fields; our extensions take their defaults)."""
    if msg_type is msgs.PositionTarget:
        return position_target(value)
    if msg_type is msgs.PoseStamped:
        pose = value["pose"]
        return msgspec.convert(
            {"header": _header(value["header"]), "pose": pose},
            msgs.PoseStamped,
            from_attributes=True,
        )
    if msg_type is msgs.TwistStamped:
        twist = value["twist"]
        return msgs.TwistStamped(
            header=_header(value["header"]),
            twist=msgs.Twist(linear=_vector(twist["linear"]), angular=_vector(twist["angular"])),
        )
    fields = {k: v for k, v in value.items() if k in msg_type.__struct_fields__}
    fields["header"] = _header(value["header"])
    if "data" in fields:
        fields["data"] = memoryview(bytes(fields["data"]))
    if msg_type is msgs.BatteryState:
        fields.pop("temperature", None)
    return msgspec.convert(fields, msg_type, from_attributes=True, strict=False)


# ---- services ----


def request_of(request_type: type, value: dict[str, Any]) -> Any:
    """Our request from a decoded ROS 2 service request; our rules check it (ValueError)."""
    if request_type is msgs.ParamSet:
        param = value["value"]
        return msgs.ParamSet(param_id=value["param_id"], value=param_value(param))
    try:
        return msgspec.convert(value, request_type)
    except msgspec.ValidationError as exc:
        raise ValueError(str(exc)) from exc


def param_value(value: dict[str, Any]) -> msgs.ParamValue:
    """ParamValue of a mavros_msgs/ParamValue (as MAVROS reads it: integer when non-zero)."""
    if value["integer"] != 0:
        return msgs.ParamValue.of(int(value["integer"]))
    return msgs.ParamValue.of(float(value["real"]))


def _result(code: int) -> int:
    return code if 0 <= code <= 255 else MAV_RESULT_FAILED


def response_of(reply: Any) -> dict[str, Any]:
    """The ROS 2 response of one of our replies."""
    if isinstance(reply, msgs.CommandBoolResult | msgs.CommandTOLResult):
        return {"success": reply.success, "result": _result(reply.result)}
    if isinstance(reply, msgs.SetModeResult):
        return {"mode_sent": reply.mode_sent}
    if isinstance(reply, msgs.ParamGetResult | msgs.ParamSetResult):
        number = reply.value.as_number()
        param = {"integer": number, "real": 0.0} if isinstance(number, int) else {"integer": 0}
        if not isinstance(number, int):
            param["real"] = number
        return {"success": reply.success, "value": param}
    raise TypeError(f"no ROS 2 response for {type(reply).__name__}")


def refusal_of(request_type: type, result: int) -> dict[str, Any]:
    """The ROS 2 response that says "refused" for a request the bridge or the gateway refused
    (``result``: a MAV_RESULT, e.g. DENIED for the lease)."""
    if request_type in (msgs.CommandBool, msgs.CommandTOL):
        return {"success": False, "result": _result(result)}
    if request_type is msgs.SetMode:
        return {"mode_sent": False}
    return {"success": False, "value": {"integer": 0, "real": 0.0}}
