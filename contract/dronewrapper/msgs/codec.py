"""Encoding at the boundary: MessagePack maps via msgspec, one cached decoder per type.

>>> from dronewrapper.msgs import PoseStamped
>>> decode(PoseStamped, encode(PoseStamped())).pose.orientation.w
1.0
"""

from __future__ import annotations

from typing import Any, TypeVar

import msgspec

T = TypeVar("T")

_encoder = msgspec.msgpack.Encoder()

DecodeError = msgspec.DecodeError
"""Raised when bytes are not a valid message of the expected type."""


def encode(msg: Any) -> bytes:
    """Serialise a message Struct to MessagePack (a self-describing map)."""
    return _encoder.encode(msg)


_DECODERS: dict[type, msgspec.msgpack.Decoder[Any]] = {}


def decoder(msg_type: type[T]) -> msgspec.msgpack.Decoder[T]:
    """The cached decoder for ``msg_type`` (made once; a race makes one twice, harmlessly)."""
    found = _DECODERS.get(msg_type)
    if found is None:
        found = _DECODERS.setdefault(msg_type, msgspec.msgpack.Decoder(msg_type))
    return found


def decode(msg_type: type[T], data: bytes | bytearray | memoryview) -> T:
    """Deserialise ``data`` as ``msg_type``; raises DecodeError/ValidationError if it is not."""
    return decoder(msg_type).decode(data)


SCHEMA_VERSION = 1
"""The version of the message schemas (the msgs package): a change that old readers cannot
decode (a field removed, renamed or retyped) takes the next number."""


def schema_name(msg_type: type) -> str:
    """The schema id carried in the Zenoh encoding and in recordings, e.g.
    ``dronewrapper/v1/PoseStamped``.

    Messages are decoded by their key's registry type, never by this name, so recordings
    whose names carry no version (``dronewrapper/PoseStamped``) decode too.
    """
    return f"dronewrapper/v{SCHEMA_VERSION}/{msg_type.__name__}"


def to_builtins(msg: Any) -> Any:
    """A message as plain dicts/lists (for printing and JSON)."""
    return msgspec.to_builtins(msg, builtin_types=(bytes, memoryview))
