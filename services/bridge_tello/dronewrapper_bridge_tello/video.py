"""The Tello's H.264 video: datagrams -> decoded frames (PyAV), newest frame only.

The Tello sends H.264 Annex-B on UDP 11111, each frame cut into datagrams of ``chunk`` (1460)
bytes, the last one shorter. :class:`FrameAssembler` joins datagrams until a short one ends the
frame (no parser: it would hold every frame back until the next one starts, +33 ms). A frame
whose size is a multiple of the chunk has no short datagram; it ends where a datagram starts a
new access unit (a start code followed by an SPS, PPS, AUD or a slice with first_mb 0).
:class:`H264Decoder` decodes each frame from the first key frame on (an SPS or an IDR slice: what
comes before it has no reference to decode against); corrupt or partial data is counted and
skipped, never raised. :class:`VideoReceiver` is both for one run of the stream: a new
``streamon`` restarts it, so no datagram of the previous run is joined to the new run's first
frame and no old picture serves as its reference. The bridge hands decoded frames to its
publisher through a :class:`~dronewrapper.runtime.Latest`: the publisher takes the newest, older
unpublished ones are skipped, so a slow consumer never builds a backlog (the most reported Tello
video problem).
"""

from __future__ import annotations

import logging
from dataclasses import dataclass
from typing import Any

import av

# FFmpeg logs every damaged slice at error level; the counts here say it once.
av.logging.set_level(av.logging.PANIC)

TELLO_CHUNK = 1460
MAX_FRAME_BYTES = 2_000_000


def starts_access_unit(datagram: bytes) -> bool:
    """True if ``datagram`` begins a new access unit: a start code, then an SPS / PPS / AUD, or
    a coded slice whose ``first_mb_in_slice`` is 0 (its first bit, ue(v) of 0, is 1)."""
    if datagram.startswith(b"\x00\x00\x00\x01"):
        i = 4
    elif datagram.startswith(b"\x00\x00\x01"):
        i = 3
    else:
        return False
    if len(datagram) < i + 2:
        return False
    nal_type = datagram[i] & 0x1F
    if nal_type in (7, 8, 9):
        return True
    return nal_type in (1, 5) and bool(datagram[i + 1] & 0x80)


class FrameAssembler:
    """Joins video datagrams into whole frames (access units); pure."""

    def __init__(self, chunk: int = TELLO_CHUNK, max_frame_bytes: int = MAX_FRAME_BYTES) -> None:
        self.chunk = chunk
        self.max_frame_bytes = max_frame_bytes
        self.oversized = 0
        self._parts: list[bytes] = []
        self._size = 0

    def _take(self) -> bytes:
        frame = b"".join(self._parts)
        self._parts, self._size = [], 0
        return frame

    def feed(self, datagram: bytes) -> list[bytes]:
        """Add one datagram; returns the frames it completes (usually none or one)."""
        out = []
        if self._parts and starts_access_unit(datagram):
            out.append(self._take())  # the previous frame was a multiple of the chunk
        self._parts.append(datagram)
        self._size += len(datagram)
        if self._size > self.max_frame_bytes:
            self.oversized += 1
            self._parts, self._size = [], 0
        elif len(datagram) < self.chunk:
            out.append(self._take())
        return out


@dataclass
class DecodeCounts:
    """What the decoder has seen: access units in, frames decoded, access units skipped as
    corrupt or as coming before the first key frame."""

    packets: int = 0
    decoded: int = 0
    corrupt: int = 0
    before_keyframe: int = 0  # access units skipped while waiting for the first key frame


class H264Decoder:
    """One H.264 decoder (PyAV / libavcodec) that starts at a key frame; corrupt input is
    counted, never raised."""

    def __init__(self, counts: DecodeCounts | None = None) -> None:
        self.counts = counts if counts is not None else DecodeCounts()
        self.keyframe_seen = False
        self._codec = self._open()

    @staticmethod
    def _open() -> Any:
        codec = av.CodecContext.create("h264", "r")
        codec.thread_type = "SLICE"  # frame threading would hold frames back
        return codec

    def decode(self, data: bytes) -> list[Any]:
        """Decode one access unit (Annex-B bytes); returns the av.VideoFrames it produced."""
        self.counts.packets += 1
        if not self.keyframe_seen:
            if not _has_nal(data, KEYFRAME_NALS):
                self.counts.before_keyframe += 1
                return []
            self.keyframe_seen = True
        try:
            frames = self._codec.decode(av.Packet(data))
        except (av.error.FFmpegError, ValueError):
            self.counts.corrupt += 1
            return []
        if not frames and not _has_nal(data, PICTURE_NALS):
            return []
        self.counts.decoded += len(frames)
        return list(frames)


class VideoReceiver:
    """One run of the stream: datagrams -> assembled frames -> decoded pictures.

    :meth:`restart` begins a new run (after an accepted ``streamon``) with a fresh assembler
    and decoder; ``runs`` counts the runs, ``counts`` is every run's decoder counts together.
    """

    def __init__(self, chunk: int = TELLO_CHUNK) -> None:
        self.chunk = chunk
        self.runs = 0
        self.counts = DecodeCounts()
        self.restart()

    def restart(self) -> None:
        """Forget the previous run: a partial frame and the decoder's reference pictures."""
        self.assembler = FrameAssembler(chunk=self.chunk)
        self.decoder = H264Decoder(self.counts)
        self.runs += 1

    def feed(self, datagram: bytes) -> list[Any]:
        """One video datagram in; the av.VideoFrames it completes out."""
        return [
            picture
            for frame in self.assembler.feed(datagram)
            for picture in self.decoder.decode(frame)
        ]


PICTURE_NALS = (1, 5)  # coded slices (non-IDR, IDR)
KEYFRAME_NALS = (5, 7)  # an IDR slice, or an SPS (which a key frame's parameters begin with)


def _has_nal(data: bytes, types: tuple[int, ...]) -> bool:
    """True if ``data`` (Annex-B) holds a NAL unit of one of ``types``."""
    index = data.find(b"\x00\x00\x01")
    while index >= 0 and index + 3 < len(data):
        if data[index + 3] & 0x1F in types:
            return True
        index = data.find(b"\x00\x00\x01", index + 3)
    return False


log = logging.getLogger("bridge_tello.video")
