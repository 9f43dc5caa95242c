"""The attachment rmw_zenoh puts on every sample, query and reply (and requires: a sample
without one is dropped, "Unable to obtain attachment").

33 bytes, zenoh-ext serialization: ``int64`` sequence number, ``int64`` source timestamp (ns
since the Unix epoch), then the 16-byte GID as a sequence (LEB128 length ``0x10``, then the
bytes). A service reply carries the request's sequence number and the client's GID back.

    >>> len(pack(1, 2, bytes(16)))
    33
"""

from __future__ import annotations

import struct
from dataclasses import dataclass

GID_SIZE = 16
_HEAD = struct.Struct("<qqB")
SIZE = _HEAD.size + GID_SIZE


class AttachmentError(ValueError):
    """An attachment that is not rmw_zenoh's."""


@dataclass(frozen=True)
class Attachment:
    sequence: int
    timestamp_ns: int
    gid: bytes


def pack(sequence: int, timestamp_ns: int, gid: bytes) -> bytes:
    """The attachment bytes for one sample (``gid``: 16 bytes)."""
    if len(gid) != GID_SIZE:
        raise AttachmentError(f"gid must be {GID_SIZE} bytes, got {len(gid)}")
    return _HEAD.pack(sequence, timestamp_ns, GID_SIZE) + gid


def unpack(raw: bytes | None) -> Attachment:
    """Read an attachment.

    Raises:
        AttachmentError: missing, or not 8 + 8 + 1 + 16 bytes with a GID length of 16.
    """
    if raw is None:
        raise AttachmentError("no attachment (rmw_zenoh sends one with every sample)")
    if len(raw) != SIZE:
        raise AttachmentError(f"attachment of {len(raw)} bytes, expected {SIZE}")
    sequence, stamp, length = _HEAD.unpack_from(raw)
    if length != GID_SIZE:
        raise AttachmentError(f"attachment gid length {length}, expected {GID_SIZE}")
    return Attachment(sequence, stamp, bytes(raw[_HEAD.size :]))
