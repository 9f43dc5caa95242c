"""A fake V4L2 capture with OpenCV's ``VideoCapture`` interface, for the camera's option handling.

It behaves like a UVC camera behind OpenCV's V4L2 backend: the pixel format is chosen first,
then the nearest size that format offers, then the nearest rate; ``get`` reads back what was
granted; ``read`` blocks for a frame period like a device, and frames carry a driver timestamp
(``CAP_PROP_POS_MSEC``, monotonic ms) 50 ms before the read. ``busy`` opens but gives no frames,
as a device another program streams from. Its time is ``clock``'s (the real clocks, or the
virtual time the service under test runs in).
"""

from __future__ import annotations

import numpy as np

from dronewrapper.runtime.clock import REAL, Clock
from dronewrapper_camera_victure import sources

EXPOSURE_AGE_S = 0.05
"""The driver timestamp of a frame is this much before its read (s)."""

VICTURE_MODES = {
    "MJPG": [(640, 480, 30.0), (1280, 720, 30.0), (1920, 1080, 30.0)],
    "YUYV": [(640, 480, 30.0), (1280, 720, 10.0)],
}


class FakeCapture:
    def __init__(
        self, modes=None, *, opened: bool = True, busy: bool = False, clock: Clock = REAL
    ) -> None:
        self.clock = clock
        self.modes = modes or VICTURE_MODES
        self.opened = opened
        self.busy = busy
        self.fmt = "YUYV"
        self.width, self.height, self.fps = self.modes["YUYV"][0]
        self.requested_width = 0
        self.sets: list[tuple[int, float]] = []
        self.reads = 0
        self.read_walls: dict[int, float] = {}  # read number -> wall clock of that read
        self._read_mono = 0.0
        self.released = False

    def isOpened(self) -> bool:
        return self.opened and not self.released

    def _pick(self) -> None:
        offered = self.modes[self.fmt]
        want_w = self.requested_width or self.width
        w, h, fps = min(offered, key=lambda m: (abs(m[0] - want_w), -m[2]))
        self.width, self.height = w, h
        self.fps = fps  # a new size starts at its highest rate

    def set(self, prop: int, value: float) -> bool:
        self.sets.append((prop, value))
        if prop == sources.CAP_PROP_FOURCC:
            text = sources.fourcc_text(value)
            if text in self.modes:
                self.fmt = text
                self._pick()
        elif prop == sources.CAP_PROP_FRAME_WIDTH:
            self.requested_width = int(value)
            self._pick()
        elif prop == sources.CAP_PROP_FPS:
            offered = [m[2] for m in self.modes[self.fmt] if m[:2] == (self.width, self.height)]
            self.fps = min(float(value), max(offered))
        return True

    def get(self, prop: int) -> float:
        return {
            sources.CAP_PROP_FRAME_WIDTH: float(self.width),
            sources.CAP_PROP_FRAME_HEIGHT: float(self.height),
            sources.CAP_PROP_FPS: self.fps,
            sources.CAP_PROP_FOURCC: float(sources.fourcc_code(self.fmt)),
            sources.CAP_PROP_POS_MSEC: (self._read_mono - EXPOSURE_AGE_S) * 1000.0,
        }.get(prop, 0.0)

    def read(self):
        self.reads += 1
        if self.busy or self.released:
            return False, None
        self.clock.sleep(1.0 / self.fps)
        self.read_walls[self.reads] = self.clock.time()
        self._read_mono = self.clock.monotonic()
        return True, np.full((self.height, self.width, 3), self.reads % 256, np.uint8)

    def release(self) -> None:
        self.released = True
