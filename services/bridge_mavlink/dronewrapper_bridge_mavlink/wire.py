"""MAVLink frames on the wire, found and sorted by message id before anything is decoded (pure).

Decoding a MAVLink message in pymavlink (CRC, ``struct`` unpack, a message object) costs about
10 µs of Python; PX4's onboard link sends messages the bridge never reads at several hundred
per second. The header alone says how long a frame is and which message it carries, so the
bridge cuts the bytes into frames here and decodes only the ids it reads:

- MAVLink 1: ``0xFE len seq sys comp msgid`` (6 bytes), the payload, a 2-byte CRC;
- MAVLink 2: ``0xFD len incompat compat seq sys comp msgid(3 bytes, little-endian)``
  (10 bytes), the payload, a 2-byte CRC, and a 13-byte signature when ``incompat`` has bit 0
  (``MAVLINK_IFLAG_SIGNED``).

:class:`FrameCutter` keeps the end of a read that holds only part of a frame for the next read
(serial and TCP links deliver a byte stream, cut anywhere); a UDP datagram holds whole frames
and is cut with :func:`cut_datagram`. Bytes before a start marker are skipped and counted. A
frame is only cut here, never checked: the CRC and the signature are checked when a kept frame
is decoded (pymavlink's ``decode``), and a dropped frame is neither checked nor counted as bad,
as a frame of an id nobody reads needs neither.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass

MARKER_V1 = 0xFE
MARKER_V2 = 0xFD
HEADER_V1 = 6
HEADER_V2 = 10
CRC_LEN = 2
SIGNATURE_LEN = 13
IFLAG_SIGNED = 0x01
MIN_HEADER = 3  # marker, payload length, and (MAVLink 2) the incompat flags


@dataclass(frozen=True)
class Frame:
    """One whole frame as it came: its message id and its bytes (header to CRC or signature)."""

    msg_id: int
    data: bytes


def frame_length(buf: bytes | bytearray, at: int) -> int:
    """The length of the frame starting at ``buf[at]`` (a start marker), from its first three
    bytes (which must be there)."""
    length = buf[at + 1]
    if buf[at] == MARKER_V1:
        return HEADER_V1 + length + CRC_LEN
    signed = SIGNATURE_LEN if buf[at + 2] & IFLAG_SIGNED else 0
    return HEADER_V2 + length + CRC_LEN + signed


def message_id(frame: bytes | bytearray) -> int:
    """The message id of a whole frame."""
    if frame[0] == MARKER_V1:
        return frame[5]
    return frame[7] | frame[8] << 8 | frame[9] << 16


def _next_marker(buf: bytes | bytearray, start: int) -> int:
    """Index of the first start marker at or after ``start``; ``len(buf)`` if none."""
    v1, v2 = buf.find(MARKER_V1, start), buf.find(MARKER_V2, start)
    found = [i for i in (v1, v2) if i >= 0]
    return min(found) if found else len(buf)


class FrameCutter:
    """Cuts a byte stream into frames, keeping an incomplete frame for the next read.

    ``skipped`` counts the bytes that were not part of any frame (noise, a frame cut off by a
    reconnect). For datagrams use :func:`cut_datagram`: no carry-over between two datagrams.
    """

    def __init__(self) -> None:
        self._buf = bytearray()
        self.skipped = 0

    @property
    def pending(self) -> int:
        """Bytes held for the next read (the start of a frame)."""
        return len(self._buf)

    def clear(self) -> None:
        """Forget what is held (the link was reopened)."""
        self._buf.clear()

    def feed(self, data: bytes | bytearray) -> list[Frame]:
        """The whole frames completed by ``data``, in order."""
        buf = self._buf
        buf += data
        frames, at = self._cut(buf, 0, final=False)
        del buf[:at]
        return frames

    def _cut(self, buf: bytes | bytearray, at: int, *, final: bool) -> tuple[list[Frame], int]:
        frames: list[Frame] = []
        end = len(buf)
        while at < end:
            marker = buf[at]
            if marker != MARKER_V1 and marker != MARKER_V2:
                nxt = _next_marker(buf, at)
                self.skipped += nxt - at
                at = nxt
                continue
            if end - at < MIN_HEADER:
                break
            size = frame_length(buf, at)
            if end - at < size:
                break
            data = bytes(buf[at : at + size])
            frames.append(Frame(message_id(data), data))
            at += size
        if final and at < end:
            self.skipped += end - at
            at = end
        return frames, at


def cut_datagram(datagram: bytes | bytearray, cutter: FrameCutter) -> list[Frame]:
    """The whole frames of one datagram; a truncated last frame is counted in the cutter's
    ``skipped`` (UDP never carries the rest of it in the next datagram)."""
    frames, _ = cutter._cut(datagram, 0, final=True)
    return frames


def wanted_ids(names: Iterable[str], dialect: object) -> frozenset[int]:
    """The ids of messages ``names`` (``LOCAL_POSITION_NED`` ...) in a pymavlink ``dialect``
    module; a name the dialect lacks is left out."""
    ids = (getattr(dialect, f"MAVLINK_MSG_ID_{name}", None) for name in names)
    return frozenset(i for i in ids if i is not None)


def sequence_of(frame: bytes | bytearray) -> tuple[int, int, int]:
    """(system id, component id, seq) from a whole frame's header."""
    if frame[0] == MARKER_V1:
        return frame[3], frame[4], frame[2]
    return frame[5], frame[6], frame[4]


class SequenceGaps:
    """Frames lost on the way, from the gaps in each sender's 8-bit ``seq``, counted over every
    frame (read or dropped), as pymavlink counts them (``mav_loss``): a sender's first frame
    starts its count; a step of k > 1 means k - 1 frames lost."""

    def __init__(self) -> None:
        self._last: dict[tuple[int, int], int] = {}
        self.lost = 0

    def add(self, frame: bytes | bytearray) -> int:
        """Count ``frame``; the frames lost just before it."""
        system, component, seq = sequence_of(frame)
        last = self._last.get((system, component))
        self._last[(system, component)] = seq
        if last is None:
            return 0
        gap = (seq - last - 1) % 256
        self.lost += gap
        return gap
