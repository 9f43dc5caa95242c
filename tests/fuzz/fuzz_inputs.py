"""Hypothesis strategies for bad input: each example is a payload that must be refused.

Every strategy starts from a valid message (one that WOULD act: arm, take off, write a
parameter) and breaks it one way: an unknown field, a missing required field, a wrongly typed
field, a non-finite or huge value, truncated bytes, random bytes, or a payload that is not a map
at all. Each example carries the fragment its error reply must contain (the field's name, or the
type's name when the bytes are unreadable), so a test can check that the reply names the problem.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import msgspec
from hypothesis import strategies as st

from dronewrapper.envelope import Envelope
from dronewrapper.msgs import codec, registry
from dronewrapper.msgs.mavros import CommandTOL
from dronewrapper.msgs.mission import Waypoint
from dronewrapper.msgs.vision import Detections

MAX_FLOAT = 1e300
MAX_INT = 2**63 - 1
_INTS = st.integers(-(2**63), 2**64 - 1)  # what MessagePack can carry


@dataclass(frozen=True)
class Bad:
    """A payload that must be refused; ``named`` must appear in the error reply."""

    payload: bytes
    named: str
    how: str

    def __repr__(self) -> str:  # hypothesis prints failing examples
        return f"Bad({self.how}: {self.payload[:80]!r}, named={self.named!r})"


@dataclass(frozen=True)
class Field:
    """One field of a request: its path in the map, its kind, and what is refused."""

    path: tuple[str, ...]
    kind: str  # float | int | bool | str
    required: bool = True
    nan_refused: bool = False  # NaN is a valid "default" for some floats (CommandTOL.yaw)
    huge_refused: bool = True  # whether a huge value is out of range for this field

    @property
    def name(self) -> str:
        return ".".join(str(part) for part in self.path)


@dataclass(frozen=True)
class RequestShape:
    """A service's request: a valid base (it would act) and its fields."""

    service: registry.Service
    base: dict
    fields: tuple[Field, ...]


WAYPOINT = Waypoint(x_lat=47.4, y_long=8.5, z_alt=5.0)


def _tol(altitude: float) -> dict:
    return msgspec.to_builtins(CommandTOL.takeoff(altitude))


REQUESTS = {
    "arming": RequestShape(registry.ARMING, {"value": True}, (Field(("value",), "bool"),)),
    "takeoff": RequestShape(
        registry.TAKEOFF,
        _tol(2.0),
        (
            Field(("min_pitch",), "float", nan_refused=True),
            Field(("yaw",), "float"),
            Field(("latitude",), "float"),
            Field(("longitude",), "float"),
            Field(("altitude",), "float"),
        ),
    ),
    "land": RequestShape(
        registry.LAND,
        msgspec.to_builtins(CommandTOL.land()),
        (
            Field(("min_pitch",), "float", nan_refused=True),
            Field(("latitude",), "float"),
            Field(("longitude",), "float"),
        ),
    ),
    "set_mode": RequestShape(
        registry.SET_MODE,
        {"base_mode": 0, "custom_mode": "AUTO.LAND"},
        (Field(("custom_mode",), "str"), Field(("base_mode",), "int", required=False)),
    ),
    "param_get": RequestShape(
        registry.PARAM_GET, {"param_id": "MPC_XY_VEL_MAX"}, (Field(("param_id",), "str"),)
    ),
    "param_set": RequestShape(
        registry.PARAM_SET,
        {"param_id": "MPC_XY_VEL_MAX", "value": {"integer": 0, "real": 5.0}},
        (
            Field(("param_id",), "str"),
            Field(("value", "real"), "float", required=False, nan_refused=True),
            Field(("value", "integer"), "int", required=False),
        ),
    ),
    "mission_push": RequestShape(
        registry.MISSION_PUSH,
        {
            "start_index": 0,
            "waypoints": [msgspec.to_builtins(WAYPOINT)],
        },
        (
            Field(("waypoints", 0, "x_lat"), "float", nan_refused=True),
            Field(("waypoints", 0, "y_long"), "float", nan_refused=True),
            Field(("waypoints", 0, "z_alt"), "float", nan_refused=True),
            Field(("waypoints", 0, "param1"), "float", required=False, nan_refused=True),
        ),
    ),
    "mission_control": RequestShape(
        registry.MISSION_CONTROL, {"action": "start"}, (Field(("action",), "str"),)
    ),
    "envelope_set": RequestShape(
        registry.ENVELOPE_SET,
        {"envelope": msgspec.to_builtins(Envelope(max_altitude=500.0))},
        (
            Field(("envelope", "max_altitude"), "float", required=False, nan_refused=True),
            Field(("envelope", "max_distance"), "float", required=False, nan_refused=True),
            Field(("envelope", "margin"), "float", required=False, nan_refused=True),
            Field(("envelope", "breach_action"), "str", required=False),
        ),
    ),
}

_WRONG_TYPES = {
    "float": st.one_of(st.text(max_size=5), st.booleans(), st.none(), st.lists(_INTS)),
    "int": st.one_of(st.text(max_size=5), st.booleans(), st.floats(), st.none()),
    "bool": st.one_of(_INTS, st.text(max_size=5), st.floats(), st.none()),
    "str": st.one_of(_INTS, st.floats(), st.booleans(), st.none(), st.lists(st.text())),
}


def _with(base: dict, path: tuple[str, ...], value: object) -> dict:
    out = msgspec.to_builtins(base)  # a deep copy
    node = out
    for key in path[:-1]:
        node = node[key]
    node[path[-1]] = value
    return out


def _without(base: dict, path: tuple[str, ...]) -> dict:
    out = msgspec.to_builtins(base)
    node = out
    for key in path[:-1]:
        node = node[key]
    del node[path[-1]]
    return out


def _encode(value: object) -> bytes:
    return msgspec.msgpack.encode(value)


@st.composite
def bad_request(draw: st.DrawFn, shape: RequestShape) -> Bad:
    """One refused payload for ``shape``'s service."""
    type_name = shape.service.request.__name__
    kinds = ["unknown", "wrong_type", "truncated", "garbage", "not_a_map"]
    if any(f.required for f in shape.fields):
        kinds.append("missing")
    if any(f.kind == "float" for f in shape.fields):
        kinds.append("non_finite")
    if any(f.huge_refused and f.kind != "bool" for f in shape.fields):
        kinds.append("huge")
    how = draw(st.sampled_from(kinds))
    base = shape.base
    if how == "unknown":
        name = draw(st.text("abcdefghijklmnopqrstuvwxyz_", min_size=1, max_size=12))
        if name in base:
            name += "_x"
        value = draw(st.one_of(_INTS, st.floats(), st.text(max_size=8), st.booleans()))
        return Bad(_encode({**base, name: value}), f"unknown field `{name}`", how)
    if how == "missing":
        field = draw(st.sampled_from([f for f in shape.fields if f.required]))
        return Bad(_encode(_without(base, field.path)), f"`{field.path[-1]}`", how)
    if how == "wrong_type":
        field = draw(st.sampled_from(shape.fields))
        value = draw(_WRONG_TYPES[field.kind])
        return Bad(_encode(_with(base, field.path, value)), field.path[-1], how)
    if how == "non_finite":
        field = draw(st.sampled_from([f for f in shape.fields if f.kind == "float"]))
        choices = [math.inf, -math.inf] + ([math.nan] if field.nan_refused else [])
        value = draw(st.sampled_from(choices))
        return Bad(_encode(_with(base, field.path, value)), field.path[-1], how)
    if how == "huge":
        hugeable = [f for f in shape.fields if f.huge_refused and f.kind != "bool"]
        field = draw(st.sampled_from(hugeable))
        value = {
            "float": draw(st.sampled_from([MAX_FLOAT, -MAX_FLOAT, 1e39])),
            "int": draw(st.sampled_from([MAX_INT, -(2**63), 2**64 - 1])),
            "str": "X" * draw(st.integers(65, 100_000)),
            "bool": True,
        }[field.kind]
        return Bad(_encode(_with(base, field.path, value)), field.path[-1], how)
    if how == "truncated":
        data = _encode(base)
        cut = draw(st.integers(0, len(data) - 1))
        return Bad(data[:cut], type_name, how)
    if how == "garbage":
        data = draw(st.binary(min_size=1, max_size=64))
        if 0x80 <= data[0] <= 0x8F or data[0] in (0xDE, 0xDF):
            data = b"\xc1" + data  # never a map (a map of random keys could be valid)
        return Bad(data, type_name, how)
    value = draw(st.one_of(_INTS, st.text(max_size=8), st.lists(_INTS, max_size=3)))
    return Bad(_encode(value), type_name, how)


# ---- setpoints: the one key the bridge subscribes to ----

SETPOINT_BASE = {
    "header": {"seq": 0, "stamp": 1.0, "frame_id": "base_link"},
    "coordinate_frame": 8,
    "type_mask": 1991,
    "position": {"x": 0.0, "y": 0.0, "z": 0.0},
    "velocity": {"x": 0.5, "y": 0.0, "z": 0.0},
    "acceleration_or_force": {"x": 0.0, "y": 0.0, "z": 0.0},
    "yaw": 0.0,
    "yaw_rate": 0.0,
}
_SETPOINT_USED = (("velocity", "x"), ("velocity", "y"), ("velocity", "z"), ("yaw_rate",))


@st.composite
def bad_setpoint(draw: st.DrawFn) -> Bad:
    """A PositionTarget payload the bridge must refuse (decode error or validation)."""
    kinds = ["wrong_type", "non_finite", "huge", "mask", "missing", "truncated", "garbage"]
    how = draw(st.sampled_from(kinds))
    if how == "missing":
        path = draw(st.sampled_from([("type_mask",), ("coordinate_frame",)]))
        return Bad(_encode(_without(SETPOINT_BASE, path)), path[-1], how)
    if how == "wrong_type":
        path = draw(st.sampled_from([*_SETPOINT_USED, ("type_mask",), ("header", "stamp")]))
        kind = "int" if path == ("type_mask",) else "float"
        value = draw(_WRONG_TYPES[kind])
        return Bad(_encode(_with(SETPOINT_BASE, path, value)), path[-1], how)
    if how in ("non_finite", "huge"):
        path = draw(st.sampled_from(_SETPOINT_USED))
        values = [math.inf, -math.inf, math.nan] if how == "non_finite" else [1e300, -1e300, 1e9]
        value = draw(st.sampled_from(values))
        return Bad(_encode(_with(SETPOINT_BASE, path, value)), path[-1], how)
    if how == "mask":
        mask = draw(st.integers(-(2**63), 2**63 - 1).filter(lambda m: m not in (3064, 1991, 1987)))
        return Bad(_encode(_with(SETPOINT_BASE, ("type_mask",), mask)), "type_mask", how)
    if how == "truncated":
        data = _encode(SETPOINT_BASE)
        return Bad(data[: draw(st.integers(0, len(data) - 1))], "PositionTarget", how)
    data = draw(st.binary(min_size=1, max_size=64))
    if 0x80 <= data[0] <= 0x8F or data[0] in (0xDE, 0xDF):
        data = b"\xc1" + data
    return Bad(data, "PositionTarget", how)


# ---- perception and controller inputs ----

NASTY_FLOATS = st.one_of(
    st.sampled_from([math.nan, math.inf, -math.inf, 1e300, -1e300, 0.0, -0.0, 5e-324]),
    st.floats(allow_nan=True, allow_infinity=True),
    st.floats(-2000, 2000),
)
SIZES = st.one_of(st.integers(-5, 5), st.integers(0, 4096), st.sampled_from([2**31, 2**62]))


def detection(draw) -> dict:
    return {
        "header": {"stamp": draw(NASTY_FLOATS), "frame_id": "cam_frontal", "seq": 0},
        "results": [
            {"hypothesis": {"class_id": draw(st.sampled_from(["person", "red", ""])),
                            "score": draw(NASTY_FLOATS)}}
        ],
        "bbox": {
            "center": {"position": {"x": draw(NASTY_FLOATS), "y": draw(NASTY_FLOATS)},
                       "theta": draw(NASTY_FLOATS)},
            "size_x": draw(NASTY_FLOATS),
            "size_y": draw(NASTY_FLOATS),
        },
        "id": draw(st.sampled_from(["", "1", "2"])),
        "circle_radius": draw(NASTY_FLOATS),
    }  # fmt: skip


@st.composite
def detections(draw) -> Detections:
    fields = {
        "header": {"stamp": draw(NASTY_FLOATS), "frame_id": "cam_frontal", "seq": 0},
        "detections": [detection(draw) for _ in range(draw(st.integers(0, 3)))],
        "image_width": draw(SIZES),
        "image_height": draw(SIZES),
        "detector": "color",
        "target_id": draw(st.sampled_from(["", "1", "2"])),
        "processing_time": draw(NASTY_FLOATS),
    }
    return codec.decode(Detections, msgspec.msgpack.encode(fields))


@st.composite
def bad_image(draw: st.DrawFn) -> bytes:
    """An Image payload perception must survive: sizes that do not match the data, odd
    encodings, non-finite stamps, huge dimensions, or not an Image at all."""
    how = draw(st.sampled_from(["geometry", "encoding", "stamp", "bytes"]))
    width, height = draw(SIZES), draw(SIZES)
    fields = {
        "header": {"stamp": 1.0, "frame_id": "cam_frontal", "seq": 0},
        "height": min(height, 2**32 - 1) if height >= 0 else 0,
        "width": min(width, 2**32 - 1) if width >= 0 else 0,
        "encoding": "bgr8",
        "is_bigendian": 0,
        "step": 0,
        "data": draw(st.binary(max_size=256)),
    }
    if how == "encoding":
        fields["encoding"] = draw(st.sampled_from(["", "rgb16", "yuv422", "X" * 1000]))
    elif how == "stamp":
        fields["header"]["stamp"] = draw(st.sampled_from([math.nan, math.inf, -math.inf, -1.0]))
        fields["width"], fields["height"] = 4, 2
        fields["data"] = bytes(24)
    elif how == "bytes":
        return draw(st.binary(max_size=64))
    return msgspec.msgpack.encode(fields)
