"""Frame sources behind one small interface: ``open``, ``read``, ``rewind``, ``release``.

:class:`OpenCVSource` covers V4L2 devices, video files and network streams (OpenCV's FFmpeg
and V4L2 backends); :class:`PatternSource` draws the test pattern. ``open`` raises
:class:`~dronewrapper_camera_victure.sources.SourceError` when the source cannot be used at all
and :class:`~dronewrapper_camera_victure.sources.SourceUnavailable` when it may come later.
"""

from __future__ import annotations

import os
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from dronewrapper.runtime.clock import REAL, Clock
from dronewrapper_camera_victure import sources
from dronewrapper_camera_victure.config import Config
from dronewrapper_camera_victure.pattern import render_pattern
from dronewrapper_camera_victure.sources import Mode, SourceError, SourceUnavailable

# FFmpeg prints every decoding hiccup of a damaged stream to stderr; the service counts them
# instead. Must be set before OpenCV initialises FFmpeg (the first capture opened).
os.environ.setdefault("OPENCV_FFMPEG_LOGLEVEL", "8")  # AV_LOG_FATAL

Factory = Callable[..., Any]
"""Makes a capture: ``factory(source, api_preference, params)`` -> a ``cv2.VideoCapture``."""


def opencv_factory(source: str | int, api: int, params: list[int]) -> Any:
    import cv2

    return cv2.VideoCapture(source, api, params)


@dataclass
class Grab:
    """One read: a frame (None when the read failed or the file ended), its wall-clock
    capture stamp (epoch s), and ``ended`` for the end of a file."""

    frame: np.ndarray | None
    stamp: float
    ended: bool = False


class PatternSource:
    """The generated test pattern at ``config.fps`` (see :mod:`pattern`), stamped by
    ``clock``."""

    kind = "pattern"

    def __init__(self, config: Config, clock: Clock = REAL) -> None:
        self.config = config
        self.clock = clock
        self.description = "pattern"
        self.mode = Mode(config.width or 640, config.height or 480, config.fps, "pattern")
        self.pace_hz = config.fps
        self.frame_count = 0
        self._counter = 0

    def open(self) -> Mode:
        try:
            render_pattern(self.mode.width, self.mode.height, 0, 0.0)
        except ValueError as exc:
            raise SourceError(str(exc)) from exc
        return self.mode

    def read(self) -> Grab:
        """The next pattern frame, stamped when it is complete (its capture time)."""
        frame = render_pattern(self.mode.width, self.mode.height, self._counter, self.clock.time())
        self._counter += 1
        return Grab(frame, self.clock.time())

    def rewind(self) -> None:
        pass

    def release(self) -> None:
        pass


class OpenCVSource:
    """A V4L2 device, a video file or a network stream through OpenCV (see the module doc);
    reads stamped and start-up waits timed by ``clock``."""

    def __init__(
        self, config: Config, factory: Factory = opencv_factory, clock: Clock = REAL
    ) -> None:
        self.config = config
        self.clock = clock
        self.kind = config.source_kind
        self.factory = factory
        self.description = (
            sources.device_path(config.location) if self.kind == "device" else config.location
        )
        self.mode = Mode(0, 0, 0.0, "")
        self.pace_hz = 0.0
        self.frame_count = 0
        self._cap: Any = None
        self._pending: Grab | None = None

    # ---- open ----

    def open(self) -> Mode:
        self.release()
        if self.kind == "device":
            return self._open_device()
        if self.kind == "file":
            return self._open_file()
        return self._open_stream()

    def _open_device(self) -> Mode:
        import cv2

        path = self.description
        sources.check_device_present(path)
        cap = self.factory(path, cv2.CAP_V4L2, [])
        if not cap.isOpened():
            raise SourceError(f"cannot open camera {path}: busy (used by another program?)")
        self._cap = cap
        c = self.config
        requested = Mode(c.width, c.height, c.fps, c.pixel_format)
        self.mode = sources.request_mode(cap, c.width, c.height, c.fps, c.pixel_format)
        mismatches = sources.mode_mismatches(requested, self.mode)
        if mismatches and c.strict_mode:
            self.release()
            raise SourceError(
                f"camera {path} does not support {' and '.join(mismatches)}; "
                f"see its modes with --list"
            )
        self._pending = self._first_frame(path)
        return self.mode

    def _first_frame(self, what: str) -> Grab:
        deadline = self.clock.monotonic() + self.config.open_timeout
        while self.clock.monotonic() < deadline:
            grab = self.read()
            if grab.frame is not None:
                return grab
            self.clock.sleep(0.05)
        self.release()
        raise SourceError(
            f"camera {what} gives no frames within {self.config.open_timeout:g} s "
            f"(busy: is another program streaming from it?)"
        )

    def _open_file(self) -> Mode:
        import cv2

        path = sources.check_file_present(self.config.location)
        cap = self.factory(str(path), cv2.CAP_FFMPEG, [])
        if not cap.isOpened():
            raise SourceError(f"cannot decode video file {path}")
        self._cap = cap
        self.mode = sources.granted_mode(cap)
        self.frame_count = max(0, int(cap.get(sources.CAP_PROP_FRAME_COUNT)))
        fps = self.mode.fps
        self.pace_hz = fps if self.config.realtime and 0 < fps <= 1000 else 0.0
        return self.mode

    def _open_stream(self) -> Mode:
        import cv2

        params = [
            cv2.CAP_PROP_OPEN_TIMEOUT_MSEC,
            int(self.config.open_timeout * 1000),
            cv2.CAP_PROP_READ_TIMEOUT_MSEC,
            int(self.config.read_timeout * 1000),
        ]
        cap = self.factory(self.config.location, cv2.CAP_FFMPEG, params)
        if not cap.isOpened():
            cap.release()
            raise SourceUnavailable(f"cannot open stream {self.config.location}")
        self._cap = cap
        self.mode = sources.granted_mode(cap)
        return self.mode

    # ---- read ----

    def read(self) -> Grab:
        if self._pending is not None:
            grab, self._pending = self._pending, None
            return grab
        if self._cap is None:
            return Grab(None, self.clock.time())
        ok, frame = self._cap.read()
        wall, mono = self.clock.time(), self.clock.monotonic()
        if not ok or frame is None:
            return Grab(None, wall, ended=self.kind == "file")
        stamp = wall
        if self.kind == "device":
            driver = sources.driver_stamp(self._cap.get(sources.CAP_PROP_POS_MSEC), wall, mono)
            stamp = driver if driver is not None else wall
        return Grab(frame, stamp)

    def rewind(self) -> None:
        """Back to the first frame of a file (reopened: seeking a damaged file is unreliable)."""
        self.open()

    def release(self) -> None:
        if self._cap is not None:
            self._cap.release()
            self._cap = None
        self._pending = None


def make_source(config: Config, factory: Factory = opencv_factory, clock: Clock = REAL):
    """The source ``config`` names, on ``clock``."""
    if config.source_kind == "pattern":
        return PatternSource(config, clock)
    return OpenCVSource(config, factory, clock)
