"""JSON schemas of the bus messages, generated from the msgspec Structs of the registry.

The Structs are shaped like the ROS messages MAVROS uses, so the schemas are too
(``header.stamp``, ``pose.position.x`` ...). Foxglove reads self-contained schemas best, so the
``$ref``s msgspec emits are inlined (the message types are not recursive). Binary fields
(``data`` of images) are base64 strings in JSON, as msgspec encodes them.

    >>> from dronewrapper.msgs import PoseStamped
    >>> json_schema(PoseStamped)["properties"]["pose"]["properties"]["position"]["type"]
    'object'
"""

from __future__ import annotations

import json
from functools import cache
from typing import Any

import msgspec

from dronewrapper.msgs import codec

SCHEMA_ENCODING = "jsonschema"
"""MCAP/Foxglove schema encoding of the JSON schemas."""


def _inline(schema: Any, defs: dict[str, Any], depth: int = 0) -> Any:
    if depth > 32:
        raise ValueError("message schema nests deeper than 32 levels (recursive type?)")
    if isinstance(schema, dict):
        ref = schema.get("$ref")
        if isinstance(ref, str) and ref.startswith("#/$defs/"):
            return _inline(defs[ref.removeprefix("#/$defs/")], defs, depth + 1)
        return {k: _inline(v, defs, depth + 1) for k, v in schema.items() if k != "$defs"}
    if isinstance(schema, list):
        return [_inline(v, defs, depth + 1) for v in schema]
    return schema


@cache
def json_schema(msg_type: type) -> dict[str, Any]:
    """The self-contained JSON schema of a message Struct (nested types inlined)."""
    raw = msgspec.json.schema(msg_type)
    schema = _inline(raw, raw.get("$defs", {}))
    schema["title"] = codec.schema_name(msg_type)
    return schema


@cache
def json_schema_bytes(msg_type: type) -> bytes:
    """:func:`json_schema` as compact UTF-8 JSON, as stored in an MCAP Schema record."""
    return json.dumps(json_schema(msg_type), separators=(",", ":")).encode()


def to_json(msg: Any) -> bytes:
    """A message as JSON bytes (NaN and infinities become ``null``; bytes become base64)."""
    return msgspec.json.encode(msg)
