"""MAVLink 2 signature check in the order PX4 (the C library) does it, for pymavlink parsers.

pymavlink's own check records a stream's timestamp before it compares the signature, so a
single forged frame carrying a future timestamp makes every genuine frame after it look
replayed (a denial of service on a signed link). :func:`verify_signed_frame` moves the
timestamp only once the signature is valid. It needs nothing but ``hashlib``; the bridge and
the simulator install it on their parsers (``parser.check_signature``).
"""

from __future__ import annotations

import hashlib
from typing import Any

REPLAY_WINDOW = 6_000_000  # 10 µs units: a new stream may start at most 1 min behind us
SIGNATURE_BYTES = 6


def verify_signed_frame(
    signing: Any, msgbuf: bytes | bytearray, src_system: int, src_component: int
) -> bool:
    """Whether a signed MAVLink 2 frame is genuine and new for its stream.

    Args:
        signing: pymavlink's ``MAVLinkSigning`` (secret_key, timestamp, stream_timestamps).
        msgbuf: the whole frame, signature included (link id, 48-bit timestamp, 6-byte MAC).
        src_system, src_component: the frame's sender (with the link id: its stream).
    """
    link_id = msgbuf[-13]
    timestamp = int.from_bytes(bytes(msgbuf[-12:-6]), "little")
    stream = (link_id, src_system, src_component)
    last = signing.stream_timestamps.get(stream)
    if last is not None and timestamp <= last:
        return False  # replayed or reordered
    if last is None and timestamp + REPLAY_WINDOW < signing.timestamp:
        return False  # a new stream too far in the past
    mac = hashlib.sha256(signing.secret_key + bytes(msgbuf[:-SIGNATURE_BYTES])).digest()
    if mac[:SIGNATURE_BYTES] != bytes(msgbuf[-SIGNATURE_BYTES:]):
        return False
    signing.stream_timestamps[stream] = timestamp
    signing.timestamp = max(signing.timestamp, timestamp)
    return True
