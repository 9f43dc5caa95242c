"""The camera service's configuration (strict: unknown keys are errors naming the key).

Every field can be set in a YAML/JSON file (``--config``) or on the command line
(``--set source=/dev/video0 --set rotate=180``). Sizes in pixels, times in seconds, rates in Hz.
"""

from __future__ import annotations

from typing import Annotated, Literal

import msgspec

from dronewrapper.msgs.registry import CAMERAS
from dronewrapper.runtime.config_ranges import FinitePositive, check_ranges
from dronewrapper_camera_victure.sources import SOURCE_KINDS, classify_source

PIXEL_FORMATS = ("", "MJPG", "YUYV")


class Config(msgspec.Struct, kw_only=True, forbid_unknown_fields=True):
    """Camera settings.

    Attributes:
        source: what to capture: a V4L2 device (``0`` or ``/dev/video0``), a video file, a
            network URL FFmpeg opens (``rtsp://``, ``http://``, ``udp://``, ``rtp://``), or
            ``pattern`` (a generated test pattern carrying a frame counter and the time).
        kind: ``auto`` (guess from ``source``) or one of ``device``, ``file``, ``url``,
            ``pattern``.
        camera: which camera key to publish on (``cam_frontal`` or ``cam_ventral``).
        width, height: requested capture size (px; 0 = the device's default). The size of the
            test pattern.
        fps: requested frame rate of a device, and the rate of the test pattern (Hz).
        pixel_format: ``MJPG`` or ``YUYV`` requested from a device ("" = the device's default).
        strict_mode: a device that grants another size or pixel format than requested is an
            error at start-up (exit 2) rather than a warning.
        loop: restart a video file at its end (False: the service ends, exit 0).
        realtime: play a video file at its own frame rate (False: as fast as it is published).
        flip: ``none``, ``horizontal``, ``vertical`` or ``both`` (applied before ``rotate``).
        rotate: clockwise rotation in degrees: 0, 90, 180 or 270 (the paper's camera was
            mounted upside down: 180).
        crop: ``[x, y, width, height]`` of the rotated frame to keep (px; empty = all).
        resize: ``[width, height]`` of the published frame (px; empty = as cropped).
        publish_raw: publish bgr8 Images on ``{ns}/{camera}/image_raw``.
        jpeg: publish JPEG on ``{ns}/{camera}/image_raw/compressed`` too (or instead, with
            ``publish_raw: false``).
        jpeg_quality: JPEG quality 1..100.
        calibration_file: camera intrinsics (ROS/OpenCV ``camera_info`` YAML) of the captured
            frame; published, adjusted for flip/rotate/crop/resize, on
            ``{ns}/{camera}/camera_info`` with every frame ("" = none).
        open_timeout: a device or stream that gives no first frame within this is an error
            at start-up (device) or a failed attempt (stream) (s).
        read_timeout: a stream or device that gives no frame for this long is lost and
            reconnected (s).
        max_read_failures: consecutive failed reads after which a source is lost.
        retry_initial, retry_max: reconnection backoff, doubling from ``retry_initial`` up to
            ``retry_max`` (s).
        status_period: how often the CameraStatus is published and counters logged (s).
    """

    source: str | int = "0"  # an int from YAML (``source: 0``) is the device index
    kind: str = "auto"
    camera: str = "cam_frontal"
    width: Annotated[int, msgspec.Meta(ge=0)] = 640
    height: Annotated[int, msgspec.Meta(ge=0)] = 480
    fps: FinitePositive = 30.0
    pixel_format: str = ""
    strict_mode: bool = True
    loop: bool = True
    realtime: bool = True
    flip: Literal["none", "horizontal", "vertical", "both"] = "none"
    rotate: Literal[0, 90, 180, 270] = 0
    crop: list[int] = msgspec.field(default_factory=list)
    resize: list[int] = msgspec.field(default_factory=list)
    publish_raw: bool = True
    jpeg: bool = False
    jpeg_quality: Annotated[int, msgspec.Meta(ge=1, le=100)] = 80
    calibration_file: str = ""
    open_timeout: FinitePositive = 10.0
    read_timeout: FinitePositive = 2.0
    max_read_failures: Annotated[int, msgspec.Meta(ge=1)] = 10
    retry_initial: FinitePositive = 0.25
    retry_max: FinitePositive = 4.0
    status_period: FinitePositive = 1.0

    def __post_init__(self) -> None:
        self.source = str(self.source)
        if not self.source.strip():
            raise ValueError("source must not be empty")
        if self.kind not in ("auto", *SOURCE_KINDS):
            raise ValueError(f"kind must be auto or one of {', '.join(SOURCE_KINDS)}")
        classify_source(self.source, self.kind)  # raises ValueError naming a bad URL scheme
        if self.camera not in CAMERAS:
            raise ValueError(f"camera must be one of {', '.join(CAMERAS)}, not {self.camera!r}")
        check_ranges(self)
        # across keys, which a Meta cannot say
        if (self.width == 0) != (self.height == 0):
            raise ValueError(
                f"width, height must both be > 0 or both 0: {self.width}x{self.height}"
            )
        if self.pixel_format.upper() not in PIXEL_FORMATS:
            raise ValueError(f"pixel_format must be MJPG or YUYV, not {self.pixel_format!r}")
        self.pixel_format = self.pixel_format.upper()
        if self.crop and (len(self.crop) != 4 or min(self.crop[:2]) < 0 or min(self.crop[2:]) <= 0):
            raise ValueError(f"crop must be [x >= 0, y >= 0, width > 0, height > 0]: {self.crop}")
        if self.resize and (len(self.resize) != 2 or min(self.resize) <= 0):
            raise ValueError(f"resize must be [width > 0, height > 0]: {self.resize}")
        if not (self.publish_raw or self.jpeg):
            raise ValueError("publish_raw and jpeg are both false: nothing to publish")
        if self.retry_max < self.retry_initial:
            raise ValueError("retry_max must be >= retry_initial")

    @property
    def location(self) -> str:
        """``source`` as text (it is made one on load): a device index or path, a file, a URL
        or a pattern."""
        return str(self.source)

    @property
    def source_kind(self) -> str:
        """The resolved kind of ``source``: device, file, url or pattern."""
        return classify_source(self.location, self.kind)
