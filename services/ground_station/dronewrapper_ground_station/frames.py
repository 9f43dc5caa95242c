"""Latest-only video: one slot per camera keeps the newest JPEG, never a queue (pure).

The bus callback puts every frame; each page's sender takes the newest when the page has drawn
the previous one (it acknowledges each frame), so a slow page or link skips frames instead of
falling behind: what it shows is never older than one frame plus its own transfer.
"""

from __future__ import annotations

import threading
from collections.abc import Callable
from dataclasses import dataclass


@dataclass(frozen=True)
class Frame:
    """One compressed camera frame.

    Attributes:
        seq: the slot's frame counter (1 for the first frame).
        stamp: capture time, seconds since the Unix epoch (``header.stamp``).
        jpeg: the compressed image bytes.
        received: when the station received it (monotonic s).
    """

    seq: int
    stamp: float
    jpeg: bytes
    received: float


class FrameSlot:
    """The newest frame of one camera, and who wants to hear of new ones (thread-safe)."""

    def __init__(self) -> None:
        self._lock = threading.Lock()
        self._frame: Frame | None = None
        self._listeners: set[Callable[[], None]] = set()

    def put(self, stamp: float, jpeg: bytes, received: float) -> None:
        """Replace the newest frame and tell every listener (called on the bus thread)."""
        with self._lock:
            seq = self._frame.seq + 1 if self._frame else 1
            self._frame = Frame(seq, stamp, jpeg, received)
            listeners = list(self._listeners)
        for notify in listeners:
            notify()

    def latest(self) -> Frame | None:
        """The newest frame, or None before the first."""
        return self._frame

    def listen(self, notify: Callable[[], None]) -> None:
        """Call ``notify()`` (from the bus thread) on every new frame."""
        with self._lock:
            self._listeners.add(notify)

    def unlisten(self, notify: Callable[[], None]) -> None:
        with self._lock:
            self._listeners.discard(notify)

    @property
    def listeners(self) -> int:
        return len(self._listeners)


def pack(frame: Frame, header: bytes) -> bytes:
    """A WebSocket binary message: 4-byte big-endian header length, JSON header, JPEG."""
    return len(header).to_bytes(4, "big") + header + frame.jpeg
