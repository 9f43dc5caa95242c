"""The reading thread: captures as fast as the source gives frames, keeps only the newest.

The source is read on its own thread into a one-slot :class:`FrameSlot`; the publisher takes
the newest frame and any frame it did not take in time is replaced (counted as dropped), so a
slow consumer never builds a queue and latency never grows. A video file played "as fast as
possible" is the exception: there the reader waits for each frame to be taken (no frame lost).

A stream or device that fails ``max_read_failures`` reads in a row, or gives nothing for
``read_timeout`` s, is lost: it is released and opened again with exponential backoff
(``retry_initial`` doubling to ``retry_max``); the state and counters go into the service's
CameraStatus. A failed read the source recovers from counts as a corrupt frame.

Time is read and waited on only through the injected clock (``dronewrapper.runtime.clock``), so
tests run the reader, pacing and backoff included, in virtual time.
"""

from __future__ import annotations

import logging
import threading
from dataclasses import dataclass, field

import cv2
import numpy as np

from dronewrapper.runtime.clock import REAL, Clock
from dronewrapper.runtime.latest import Latest
from dronewrapper_camera_victure.capture import Grab
from dronewrapper_camera_victure.config import Config
from dronewrapper_camera_victure.sources import Mode, SourceError, SourceUnavailable

log = logging.getLogger("camera_victure")

CONNECTING, STREAMING, RECONNECTING, ENDED = "connecting", "streaming", "reconnecting", "ended"


@dataclass
class Captured:
    """A frame as captured: bgr8 pixels, the capture stamp (epoch s), its number from 0."""

    frame: np.ndarray
    stamp: float
    number: int


FrameSlot = Latest[Captured]
"""The one-slot hand-over from the reader to the publisher: the runtime's newest-value holder
(``update(frame, wait_taken=stop)`` for a lossless hand-over, ``take`` for the newest)."""


class Backoff:
    """Reconnection delays: ``initial``, doubling up to ``maximum`` (s); reset on success."""

    def __init__(self, initial: float, maximum: float) -> None:
        self.initial = initial
        self.maximum = maximum
        self._next = initial

    def next(self) -> float:
        delay = self._next
        self._next = min(self.maximum, self._next * 2)
        return delay

    def reset(self) -> None:
        self._next = self.initial


@dataclass
class CaptureStats:
    """What the reader did (read by the publisher for the status)."""

    state: str = CONNECTING
    mode: Mode = field(default_factory=lambda: Mode(0, 0, 0.0, ""))
    frames_captured: int = 0
    corrupt_frames: int = 0
    bad_frames: int = 0
    reconnects: int = 0
    open_failures: int = 0
    truncated: int = 0
    last_error: str = ""


def to_bgr(frame: np.ndarray) -> np.ndarray | None:
    """``frame`` as (h, w, 3) uint8 BGR (grey and BGRA converted), None when unusable."""
    if not isinstance(frame, np.ndarray) or frame.dtype != np.uint8 or frame.size == 0:
        return None
    if frame.ndim == 2:
        return cv2.cvtColor(frame, cv2.COLOR_GRAY2BGR)
    if frame.ndim == 3 and frame.shape[2] == 3:
        return frame
    if frame.ndim == 3 and frame.shape[2] == 4:
        return cv2.cvtColor(frame, cv2.COLOR_BGRA2BGR)
    return None


class Reader:
    """Reads ``source`` into ``slot`` on its own thread until ``stop`` is set or a file played
    once ends.

    ``opened``: the source was already opened (by the service, at start-up). ``clock``: what it
    reads the time from and waits on (the real clocks unless a test gives another).
    """

    def __init__(
        self,
        source,
        config: Config,
        slot: FrameSlot,
        stop: threading.Event,
        *,
        opened: bool,
        clock: Clock = REAL,
    ) -> None:
        self.clock = clock
        self._thread = clock.thread(self.run, "camera-reader")
        self.source = source
        self.config = config
        self.slot = slot
        self.stop = stop
        self.stats = CaptureStats(state=STREAMING if opened else CONNECTING)
        self.failure: Exception | None = None
        if opened:
            self.stats.mode = source.mode
        self._opened = opened
        self._ever_opened = opened
        self._backoff = Backoff(config.retry_initial, config.retry_max)
        self._lossless = source.kind == "file" and not config.realtime
        self._failures = 0
        self._last_frame = clock.monotonic()
        self._pass_frames = 0
        self._due = 0.0

    def start(self) -> None:
        self._thread.start()

    def is_alive(self) -> bool:
        return self._thread.is_alive()

    def join(self, timeout: float | None = None) -> None:
        """Wait up to ``timeout`` s (on the clock) for the reading thread to end."""
        self._thread.join(timeout)

    def run(self) -> None:
        try:
            while not self.stop.is_set():
                if not self._opened and not self._open():
                    continue
                if not self._read_one():
                    break
        except Exception as exc:  # a bug or an OpenCV error: the service exits 1, not silently
            log.exception("camera reader failed")
            self.failure = exc
        finally:
            self.source.release()

    def _error(self, text: str) -> None:
        if text != self.stats.last_error:
            log.warning("%s", text)
        self.stats.last_error = text

    def _open(self) -> bool:
        try:
            self.stats.mode = self.source.open()
        except (SourceError, SourceUnavailable) as exc:
            self.stats.open_failures += 1
            self._error(str(exc))
            self.clock.wait(self.stop, self._backoff.next())
            return False
        if self._ever_opened:
            self.stats.reconnects += 1
            log.info("%s open again: %s", self.source.description, self.stats.mode)
        else:
            log.info("%s open: %s", self.source.description, self.stats.mode)
        self._ever_opened = True
        self._opened = True
        self._failures = 0
        self._last_frame = self.clock.monotonic()
        self._due = 0.0
        self.stats.state = STREAMING
        return True

    def _lost(self, why: str) -> None:
        self._error(f"{self.source.description} lost: {why}; reconnecting")
        self.source.release()
        self._opened = False
        self.stats.state = RECONNECTING
        self.clock.wait(self.stop, self._backoff.next())

    def _pace(self) -> None:
        """Sleep until the next frame is due at the source's own rate (files, pattern)."""
        if not self.source.pace_hz:
            return
        period = 1.0 / self.source.pace_hz
        now = self.clock.monotonic()
        if self._due == 0.0 or now - self._due > period:
            self._due = now  # first frame, or fell behind: no burst to catch up
        elif self._due > now:
            self.clock.wait(self.stop, self._due - now)
        self._due += period

    def _read_one(self) -> bool:
        """Read one frame; False when the reader is done (a file played once ended)."""
        self._pace()
        grab: Grab = self.source.read()
        if grab.ended:
            return self._end_of_file()
        frame = to_bgr(grab.frame) if grab.frame is not None else None
        if grab.frame is not None and frame is None:
            self.stats.bad_frames += 1
        if frame is None:
            self._failures += 1
            silent = self.clock.monotonic() - self._last_frame
            if self._failures >= self.config.max_read_failures:
                self._lost(f"{self._failures} failed reads in a row")
            elif silent >= self.config.read_timeout:
                self._lost(f"no frame for {silent:.1f} s")
            return True
        if self._failures:
            self.stats.corrupt_frames += self._failures  # failed reads it recovered from
            self._failures = 0
        self._backoff.reset()
        self._last_frame = self.clock.monotonic()
        number = self.stats.frames_captured
        self.stats.frames_captured += 1
        self._pass_frames += 1
        self.stats.state = STREAMING
        self.slot.update(
            Captured(frame, grab.stamp, number), wait_taken=self.stop if self._lossless else None
        )
        return True

    def _end_of_file(self) -> bool:
        expected = self.source.frame_count
        if expected and self._pass_frames < expected - 1:  # headers may round by one
            self.stats.truncated += 1
            self._error(
                f"{self.source.description} ended at frame {self._pass_frames} of {expected} "
                f"(truncated or damaged)"
            )
        empty = self._pass_frames == 0
        self._pass_frames = 0
        if not self.config.loop:
            self.stats.state = ENDED
            log.info("end of %s", self.source.description)
            return False
        if empty:  # nothing decodable in the whole file: do not spin on it
            self.clock.wait(self.stop, self._backoff.next())
        try:
            self.source.rewind()
        except (SourceError, SourceUnavailable) as exc:  # the file vanished meanwhile
            self._opened = False
            self.stats.open_failures += 1
            self._error(str(exc))
            self.clock.wait(self.stop, self._backoff.next())
        return True
