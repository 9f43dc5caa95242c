"""CDR payloads as rmw_zenoh sends them: the 4-byte encapsulation header ``00 01 00 00``
(CDR, little endian), then the message in classic CDR (XCDR1): each primitive aligned to its
size from the end of the header, strings as uint32 length (with the NUL) + bytes + NUL,
sequences as uint32 count + elements, fixed arrays as elements only.

A message value is a dict of field name -> value (nested dicts for nested messages, lists for
arrays; ``uint8[]``/``byte[]`` fields are ``bytes``-like). Missing fields encode as zero, empty
or false.

    >>> encode("builtin_interfaces/msg/Time", {"sec": 1, "nanosec": 2}).hex()
    '000100000100000002000000'
"""

from __future__ import annotations

import struct
from collections.abc import Callable
from functools import cache
from typing import Any

from dronewrapper_ros2_codec.interfaces import ARRAY, BOUNDED, SCALAR, Field, message

HEADER = b"\x00\x01\x00\x00"
"""The encapsulation header: CDR_LE, options 0."""

_FORMATS = {
    "bool": "?",
    "byte": "B",
    "char": "B",
    "int8": "b",
    "uint8": "B",
    "int16": "h",
    "uint16": "H",
    "int32": "i",
    "uint32": "I",
    "int64": "q",
    "uint64": "Q",
    "float32": "f",
    "float64": "d",
}
_BYTES = ("uint8", "byte", "char")
_U32 = struct.Struct("<I")


class CdrError(ValueError):
    """A payload is not a valid CDR encoding of the expected type (the message says where)."""


Encoder = Callable[[bytearray, Any], None]
Decoder = Callable[[memoryview, int], tuple[Any, int]]


def _pad(buf: bytearray, align: int) -> None:
    extra = (len(buf) - 4) % align
    if extra:
        buf.extend(b"\x00" * (align - extra))


def _primitive_encoder(base: str) -> Encoder:
    if base == "string":

        def put_string(buf: bytearray, value: Any) -> None:
            raw = (value or "").encode()
            _pad(buf, 4)
            buf += _U32.pack(len(raw) + 1)
            buf += raw
            buf.append(0)

        return put_string
    packer = struct.Struct("<" + _FORMATS[base])
    size = packer.size

    def put(buf: bytearray, value: Any) -> None:
        _pad(buf, size)
        buf += packer.pack(value if value is not None else 0)

    return put


def _field_encoder(f: Field) -> Encoder:
    one = _message_encoder(f.base) if f.nested else _primitive_encoder(f.base)
    if f.kind == SCALAR:
        return one
    fixed = f.kind == ARRAY
    if f.base in _BYTES:

        def put_bytes(buf: bytearray, value: Any) -> None:
            raw = bytes(value or b"")
            if fixed:
                raw = raw[: f.size].ljust(f.size, b"\x00")
            else:
                _pad(buf, 4)
                buf += _U32.pack(len(raw))
            buf += raw

        return put_bytes
    if not f.nested and f.base != "string":
        code = _FORMATS[f.base]
        size = struct.calcsize(code)

        def put_numbers(buf: bytearray, value: Any) -> None:
            items = list(value or ())
            if fixed:
                items = (items + [0] * f.size)[: f.size]
            else:
                _pad(buf, 4)
                buf += _U32.pack(len(items))
            if items:
                _pad(buf, size)
                buf += struct.pack(f"<{len(items)}{code}", *items)

        return put_numbers

    def put_items(buf: bytearray, value: Any) -> None:
        items = list(value or ())
        if fixed:
            items = (items + [None] * f.size)[: f.size]
        else:
            if f.kind == BOUNDED and len(items) > f.size:
                raise CdrError(f"{f.name}: {len(items)} items, at most {f.size}")
            _pad(buf, 4)
            buf += _U32.pack(len(items))
        for item in items:
            one(buf, item)

    return put_items


@cache
def _message_encoder(name: str) -> Encoder:
    fields = [(f.name, _field_encoder(f)) for f in message(name).fields]

    def put_message(buf: bytearray, value: Any) -> None:
        value = value or {}
        for field_name, put in fields:
            put(buf, value.get(field_name))

    return put_message


def encode(name: str, value: dict[str, Any]) -> bytes:
    """The CDR payload (with its header) of ``value`` as message type ``name``."""
    buf = bytearray(HEADER)
    _message_encoder(name)(buf, value)
    return bytes(buf)


# ---- decoding ----


def _align(offset: int, size: int) -> int:
    extra = (offset - 4) % size
    return offset + (size - extra if extra else 0)


def _need(data: memoryview, offset: int, size: int, what: str) -> None:
    if offset + size > len(data):
        raise CdrError(f"{what}: payload ends at byte {len(data)}, needs {offset + size}")


def _primitive_decoder(base: str, what: str) -> Decoder:
    if base == "string":

        def get_string(data: memoryview, offset: int) -> tuple[Any, int]:
            offset = _align(offset, 4)
            _need(data, offset, 4, what)
            (length,) = _U32.unpack_from(data, offset)
            offset += 4
            _need(data, offset, length, what)
            if length == 0 or data[offset + length - 1] != 0:
                raise CdrError(f"{what}: string without its terminating NUL")
            text = bytes(data[offset : offset + length - 1]).decode("utf-8", "replace")
            return text, offset + length

        return get_string
    unpacker = struct.Struct("<" + _FORMATS[base])
    size = unpacker.size

    def get(data: memoryview, offset: int) -> tuple[Any, int]:
        offset = _align(offset, size)
        _need(data, offset, size, what)
        return unpacker.unpack_from(data, offset)[0], offset + size

    return get


def _field_decoder(f: Field, owner: str) -> Decoder:
    what = f"{owner}.{f.name}"
    one = _message_decoder(f.base) if f.nested else _primitive_decoder(f.base, what)
    if f.kind == SCALAR:
        return one
    fixed = f.kind == ARRAY

    def count(data: memoryview, offset: int) -> tuple[int, int]:
        if fixed:
            return f.size, offset
        offset = _align(offset, 4)
        _need(data, offset, 4, what)
        (n,) = _U32.unpack_from(data, offset)
        if f.kind == BOUNDED and n > f.size:
            raise CdrError(f"{what}: {n} items, at most {f.size}")
        if n > len(data):
            raise CdrError(f"{what}: {n} items cannot fit in {len(data)} bytes")
        return n, offset + 4

    if f.base in _BYTES:

        def get_bytes(data: memoryview, offset: int) -> tuple[Any, int]:
            n, offset = count(data, offset)
            _need(data, offset, n, what)
            return data[offset : offset + n], offset + n

        return get_bytes
    if not f.nested and f.base != "string":
        code = _FORMATS[f.base]
        size = struct.calcsize(code)

        def get_numbers(data: memoryview, offset: int) -> tuple[Any, int]:
            n, offset = count(data, offset)
            if n == 0:
                return [], offset
            offset = _align(offset, size)
            _need(data, offset, n * size, what)
            return list(struct.unpack_from(f"<{n}{code}", data, offset)), offset + n * size

        return get_numbers

    def get_items(data: memoryview, offset: int) -> tuple[Any, int]:
        n, offset = count(data, offset)
        items = []
        for _ in range(n):
            item, offset = one(data, offset)
            items.append(item)
        return items, offset

    return get_items


@cache
def _message_decoder(name: str) -> Decoder:
    fields = [(f.name, _field_decoder(f, name)) for f in message(name).fields]

    def get_message(data: memoryview, offset: int) -> tuple[Any, int]:
        value = {}
        for field_name, get in fields:
            value[field_name], offset = get(data, offset)
        return value, offset

    return get_message


def decode(name: str, payload: bytes | memoryview) -> dict[str, Any]:
    """The message of type ``name`` in a CDR payload (with its header).

    Raises:
        CdrError: not CDR little endian, or too short for the type.
    """
    data = memoryview(payload)
    if len(data) < 4 or bytes(data[:2]) != HEADER[:2]:
        raise CdrError(f"{name}: not a little-endian CDR payload (header {bytes(data[:4]).hex()})")
    value, _ = _message_decoder(name)(data, 4)
    return value
