"""A serial line's timing, and MAVLink frames cut out of a byte stream (pure; time injected).

A UART at ``baud`` with 8N1 framing carries ``baud / 10`` bytes a second (a start bit, eight
data bits, a stop bit). :class:`SerialLine` is one direction of such a line with the sender's
transmit buffer in front of it: a frame is taken whole when it fits in the buffer and dropped
whole when it does not (what an autopilot's MAVLink sender does when its serial buffer is
full), and bytes leave the buffer at the line's rate. :class:`FrameCutter` cuts a byte stream
into whole MAVLink 1 / 2 frames, so that a peer reading one frame per UDP datagram gets them
whole.
"""

from __future__ import annotations

import collections

BITS_PER_BYTE = 10
"""8N1: a start bit, eight data bits, a stop bit."""

DEFAULT_BUFFER_BYTES = 1024
"""The sender's transmit buffer, bytes (PX4 and ArduPilot keep about this much per UART)."""

MAVLINK1_STX, MAVLINK2_STX = 0xFE, 0xFD
SIGNED_FLAG = 0x01
SIGNATURE_BYTES = 13


def line_rate(baud: int) -> float:
    """Bytes a second a UART at ``baud`` carries (8N1)."""
    if baud <= 0:
        raise ValueError(f"baud must be > 0, got {baud!r}")
    return baud / BITS_PER_BYTE


class SerialLine:
    """One direction of a serial line: a bounded transmit buffer drained at ``baud / 10`` B/s.

    Args:
        baud: the line's baud rate (bits/s).
        buffer_bytes: the sender's transmit buffer; a frame that would overflow it is dropped.
        now: the time it starts (monotonic s).
    """

    def __init__(self, baud: int, *, buffer_bytes: int = DEFAULT_BUFFER_BYTES, now: float) -> None:
        self.rate = line_rate(baud)
        self.buffer_bytes = buffer_bytes
        self._queue = bytearray()
        self._credit = 0.0  # bytes the line could have carried since the last take
        self._last = now
        self.carried = 0  # bytes that went over the line
        self.dropped_frames = 0
        self.dropped_bytes = 0
        self._ends: collections.deque[tuple[int, float]] = collections.deque()  # frame ends
        self.delays: collections.deque[float] = collections.deque(maxlen=4096)
        """s from each frame's offer to its last byte over the line (the latest 4096)."""

    @property
    def queued(self) -> int:
        """Bytes waiting in the transmit buffer."""
        return len(self._queue)

    def offer(self, frame: bytes, now: float) -> bool:
        """Queue ``frame`` whole; False (and counted) when the buffer has no room for it."""
        self._advance(now)
        if len(self._queue) + len(frame) > self.buffer_bytes:
            self.dropped_frames += 1
            self.dropped_bytes += len(frame)
            return False
        self._queue += frame
        self._ends.append((self.carried + len(self._queue), now))
        return True

    def take(self, now: float) -> bytes:
        """The bytes that have gone over the line since the last take."""
        self._advance(now)
        count = min(int(self._credit), len(self._queue))
        out = bytes(self._queue[:count])
        del self._queue[:count]
        self._credit -= count
        self.carried += count
        while self._ends and self._ends[0][0] <= self.carried:
            self.delays.append(now - self._ends.popleft()[1])
        return out

    def next_byte_in(self, now: float) -> float | None:
        """Seconds until the next queued byte has gone over (None when nothing is queued)."""
        if not self._queue:
            return None
        self._advance(now)
        return max(0.0, (1.0 - self._credit) / self.rate)

    def _advance(self, now: float) -> None:
        elapsed = max(0.0, now - self._last)
        self._last = now
        self._credit += elapsed * self.rate
        if not self._queue:
            self._credit = min(self._credit, 1.0)  # an idle line saves up no bytes


def frame_length(head: bytes) -> int | None:
    """The whole length of the MAVLink frame starting ``head`` (its first 3 bytes at least),
    or None when ``head`` does not start a frame or is too short to tell."""
    if len(head) < 3:
        return None
    if head[0] == MAVLINK2_STX:
        signed = SIGNATURE_BYTES if head[2] & SIGNED_FLAG else 0
        return 10 + head[1] + 2 + signed
    if head[0] == MAVLINK1_STX:
        return 6 + head[1] + 2
    return None


class FrameCutter:
    """Whole MAVLink frames out of a byte stream; bytes before a start byte are skipped."""

    def __init__(self) -> None:
        self._buf = bytearray()
        self.skipped = 0  # bytes that started no frame

    def feed(self, data: bytes) -> list[bytes]:
        """The frames completed by ``data`` (a frame's bytes may come over several calls)."""
        self._buf += data
        frames = []
        while self._buf:
            if self._buf[0] not in (MAVLINK1_STX, MAVLINK2_STX):
                start = next(
                    (i for i, b in enumerate(self._buf) if b in (MAVLINK1_STX, MAVLINK2_STX)),
                    len(self._buf),
                )
                self.skipped += start
                del self._buf[:start]
                continue
            length = frame_length(bytes(self._buf[:3]))
            if length is None or len(self._buf) < length:
                break
            frames.append(bytes(self._buf[:length]))
            del self._buf[:length]
        return frames
