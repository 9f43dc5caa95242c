"""RIHS01 type hashes (REP-2011): what ROS 2 Jazzy and later put in every topic key.

The hash is the SHA-256 of the type description as compact JSON (``", "`` and ``": "``
separators, no default values): the type's fields, then every type it refers to, sorted by
name. A service's description has three nested fields (``request_message``,
``response_message``, ``event_message``) and refers to its Request, Response and Event
messages. ROS 2 Humble has no type hashes: rmw_zenoh there writes ``TypeHashNotSupported``.

    >>> type_hash("builtin_interfaces/msg/Time")[:15]
    'RIHS01_b106235e'
"""

from __future__ import annotations

import hashlib
import json
from functools import cache
from typing import Any

from dronewrapper_ros2_codec.interfaces import (
    ARRAY,
    BOUNDED,
    SEQUENCE,
    SERVICES,
    Field,
    dependencies,
    message,
    service_messages,
)

PREFIX = "RIHS01_"
HUMBLE = "TypeHashNotSupported"
"""What ROS 2 Humble's rmw_zenoh writes where later distros write a RIHS01 hash."""

_TYPE_IDS = {
    "int8": 2,
    "uint8": 3,
    "char": 3,  # .msg ``char`` is IDL uint8
    "int16": 4,
    "uint16": 5,
    "int32": 6,
    "uint32": 7,
    "int64": 8,
    "uint64": 9,
    "float32": 10,
    "float64": 11,
    "bool": 15,
    "byte": 16,
    "string": 17,
}
_NESTED = 1
_BOUNDED_STRING = 21
_KIND_OFFSET = {ARRAY: 48, BOUNDED: 96, SEQUENCE: 144}


def field_description(f: Field) -> dict[str, Any]:
    """One field as type_description_interfaces/Field (without its default value)."""
    if f.nested:
        type_id = _NESTED
    elif f.base == "string" and f.string_capacity:
        type_id = _BOUNDED_STRING
    else:
        type_id = _TYPE_IDS[f.base]
    type_id += _KIND_OFFSET.get(f.kind, 0)
    return {
        "name": f.name,
        "type": {
            "type_id": type_id,
            "capacity": f.size if f.kind in (ARRAY, BOUNDED) else 0,
            "string_capacity": f.string_capacity,
            "nested_type_name": f.base if f.nested else "",
        },
    }


def individual_description(name: str) -> dict[str, Any]:
    """type_description_interfaces/IndividualTypeDescription of one message type."""
    return {"type_name": name, "fields": [field_description(f) for f in message(name).fields]}


def type_description(name: str) -> dict[str, Any]:
    """The full description of a message or service type (itself and every type it uses)."""
    if name in SERVICES:
        parts = sorted(service_messages(name))
        own = {
            "type_name": name,
            "fields": [
                field_description(Field(field, part))
                for field, part in zip(
                    ("request_message", "response_message", "event_message"),
                    (f"{name}_Request", f"{name}_Response", f"{name}_Event"),
                    strict=True,
                )
            ],
        }
        referenced = set(parts)
        for part in parts:
            referenced.update(dependencies(part))
        return {
            "type_description": own,
            "referenced_type_descriptions": [individual_description(n) for n in sorted(referenced)],
        }
    return {
        "type_description": individual_description(name),
        "referenced_type_descriptions": [individual_description(n) for n in dependencies(name)],
    }


@cache
def type_hash(name: str) -> str:
    """``RIHS01_<64 hex>`` of a message (``pkg/msg/Name``) or service (``pkg/srv/Name``)."""
    text = json.dumps(type_description(name), separators=(", ", ": "), ensure_ascii=True)
    return PREFIX + hashlib.sha256(text.encode()).hexdigest()
