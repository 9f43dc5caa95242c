"""Bus samples from a Zenoh session into a :class:`~.recorder.Recorder`.

Zenoh delivers samples on its own threads; they go into a bounded queue and are written (and
JPEG-compressed) on the caller's thread, so a slow disk never stalls the session. When the queue
is full the sample is dropped and counted: recording never holds up the bus.
"""

from __future__ import annotations

import queue
import threading
import time
from collections import Counter
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

import zenoh

from dronewrapper.msgs.registry import IMAGE_COMPRESSED, IMAGE_RAW
from dronewrapper.record.pump import Queued, pump
from dronewrapper.record.recorder import Recorder

QUEUE_SIZE = 512
"""Samples waiting to be written before new ones are dropped."""


@dataclass
class CaptureStats:
    """What a capture did: samples received, written, dropped (queue full or rate-limited)."""

    received: int = 0
    written: int = 0
    dropped: Counter[str] = field(default_factory=Counter)


class ImageThrottle:
    """Keeps at most ``rate_hz`` camera frames per second per key (0: all); time injected."""

    def __init__(self, rate_hz: float) -> None:
        if rate_hz < 0:
            raise ValueError(f"image rate must be >= 0 Hz, got {rate_hz}")
        self.period = 1.0 / rate_hz if rate_hz > 0 else 0.0
        self._next: dict[str, float] = {}

    def keep(self, key: str, now: float) -> bool:
        """True if a frame on ``key`` arriving at ``now`` (s) is recorded."""
        if self.period == 0.0 or not (IMAGE_RAW.match(key) or IMAGE_COMPRESSED.match(key)):
            return True
        due = self._next.get(key)
        if due is not None and now + 1e-6 < due:
            return False
        # step from the due time while on schedule, so the mean rate holds with jittered
        # arrivals; from now after a gap (or the first frame), so no burst catches up
        start = due if due is not None and now - due < self.period else now
        self._next[key] = start + self.period
        return True


class OneStreamPerCamera:
    """With raw frames stored as JPEG, a camera's own JPEG stream would store each frame twice:
    once a camera's raw frames arrive, its ``image_raw/compressed`` samples are left out."""

    def __init__(self, enabled: bool) -> None:
        self.enabled = enabled
        self._raw: set[str] = set()  # ``{ns}/{camera}`` prefixes whose raw frames arrive

    def keep(self, key: str) -> bool:
        """True if a sample on ``key`` is recorded."""
        if not self.enabled:
            return True
        if IMAGE_RAW.match(key):
            self._raw.add(key.removesuffix("/image_raw"))
            return True
        if IMAGE_COMPRESSED.match(key):
            return key.removesuffix("/image_raw/compressed") not in self._raw
        return True


def capture(
    session: zenoh.Session,
    keyexprs: Sequence[str],
    recorder: Recorder,
    stop: threading.Event,
    *,
    duration: float = 0.0,
    image_rate_hz: float = 0.0,
) -> CaptureStats:
    """Record every sample on ``keyexprs`` until ``stop`` is set or ``duration`` s (0: no limit).

    Samples are stamped with their receive time (wall clock, ns since the epoch). When the
    recorder stores raw frames as JPEG, a camera's own JPEG stream is left out (counted as
    dropped ``duplicate_image``).
    """
    stats = CaptureStats()
    samples: queue.Queue[Queued] = queue.Queue(QUEUE_SIZE)
    throttle = ImageThrottle(image_rate_hz)
    once = OneStreamPerCamera(recorder.jpeg_quality is not None)
    lock = threading.Lock()

    def on_sample(sample: zenoh.Sample) -> None:
        key = str(sample.key_expr)
        now_ns = time.time_ns()
        with lock:
            stats.received += 1
            if not once.keep(key):
                stats.dropped["duplicate_image"] += 1
                return
            if not throttle.keep(key, now_ns / 1e9):
                stats.dropped["rate"] += 1
                return
        try:
            samples.put_nowait((key, sample.payload.to_bytes(), now_ns))
        except queue.Full:
            with lock:
                stats.dropped["queue_full"] += 1

    def write(key: str, payload: bytes, log_ns: int) -> None:
        recorder.write(key, payload, log_ns)
        stats.written += 1

    try:
        pump(session, keyexprs, on_sample, samples, write, stop, duration)
    finally:
        while True:  # what was already received is written
            try:
                write(*samples.get_nowait())
            except queue.Empty:
                break
    return stats


class BackgroundRecording:
    """A recording made on a thread of its own, from an open session (for apps and the demo).

    with BackgroundRecording(session, ["drone/**"], "flight.mcap", jpeg_quality=80):
        ...                                  # fly; the file is complete after the block
    """

    def __init__(
        self,
        session: zenoh.Session,
        keyexprs: Sequence[str],
        path: str | Path,
        *,
        jpeg_quality: int | None = 80,
        image_rate_hz: float = 0.0,
    ) -> None:
        self.path = Path(path)
        self.stats = CaptureStats()
        self._file = self.path.open("wb")
        self.recorder = Recorder(self._file, jpeg_quality=jpeg_quality)
        self._stop = threading.Event()

        def run() -> None:
            self.stats = capture(
                session, keyexprs, self.recorder, self._stop, image_rate_hz=image_rate_hz
            )

        self._thread = threading.Thread(target=run, name="recording", daemon=True)
        self._thread.start()

    def __enter__(self) -> BackgroundRecording:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def close(self, timeout: float = 10.0) -> None:
        """Stop recording and complete the file (summary and footer)."""
        self._stop.set()
        self._thread.join(timeout)
        self.recorder.close()
        self._file.close()
