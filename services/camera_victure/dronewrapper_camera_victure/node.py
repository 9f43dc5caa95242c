"""The camera_victure process: a camera, file, stream or test pattern published on Zenoh.

Frames go out exactly as the simulator publishes its own cameras: ``bgr8`` Images on
``{ns}/{camera}/image_raw`` (while someone subscribes) and JPEG on ``.../image_raw/compressed``
(always with ``jpeg: true``, else while someone subscribes), ``header.stamp`` the capture time
(the driver's timestamp when a V4L2 device gives one), ``header.frame_id`` the camera name,
``header.seq`` the capture number. With a calibration file, a CameraInfo for the frame as
published goes on ``{ns}/{camera}/camera_info`` with every frame (same header). A CameraStatus
goes on ``{ns}/{camera}/camera_status`` every ``status_period``.

Start-up: a missing or busy device, an unsupported mode, a missing file or a bad calibration is
a clear error naming it, exit 2. A stream that is not up yet is retried (state
``connecting``). The process announces itself ready after its first published frame.

Time (stamps, pacing, periods, timeouts, backoff) is read and waited on only through the
node's clock (the real clocks on a Node; tests run the service in virtual time on the fake
bus).
"""

from __future__ import annotations

import logging

import numpy as np

from dronewrapper.images import bgr_to_image, bgr_to_jpeg
from dronewrapper.msgs import registry
from dronewrapper.msgs.sensor import CameraInfo, CameraStatus
from dronewrapper.msgs.std import Header
from dronewrapper.runtime.contract import NodeApi
from dronewrapper.runtime.ports import Ports
from dronewrapper_camera_victure.calibration import (
    CalibrationError,
    Intrinsics,
    load_calibration,
    transformed,
)
from dronewrapper_camera_victure.capture import Factory, make_source, opencv_factory
from dronewrapper_camera_victure.config import Config
from dronewrapper_camera_victure.reader import Captured, FrameSlot, Reader
from dronewrapper_camera_victure.sources import SourceError
from dronewrapper_camera_victure.transform import Transform

log = logging.getLogger("camera_victure")

WAIT_S = 0.2
"""Longest wait for a frame (s), so a stop request and the status period are seen promptly."""

CLOSE_WAIT_S = 3.0
"""Longest wait for the reading thread at exit (s)."""

LOG_EVERY = 10
"""Counters are logged every this many status periods."""


def transform_of(config: Config) -> Transform:
    return Transform(
        flip=config.flip,
        rotate=config.rotate,
        crop=tuple(config.crop) if config.crop else None,  # type: ignore[arg-type]
        resize=tuple(config.resize) if config.resize else None,  # type: ignore[arg-type]
    )


class CameraService:
    """Publishes the newest captured frame (see the module doc).

    Raises (at construction):
        CalibrationError: the calibration file is missing or malformed.
    """

    def __init__(
        self,
        node: NodeApi,
        config: Config,
        factory: Factory = opencv_factory,
    ) -> None:
        self.node = node
        self.config = config
        self.clock = clock = node.clock
        self.transform = transform_of(config)
        self.calibration = (
            load_calibration(config.calibration_file) if config.calibration_file else None
        )
        self._info_for: tuple[tuple[int, int], Intrinsics] | None = None
        camera = config.camera
        self.raw = node.publisher(registry.IMAGE_RAW, camera=camera) if config.publish_raw else None
        self.jpeg = node.publisher(registry.IMAGE_COMPRESSED, camera=camera)
        self.info = (
            node.publisher(registry.CAMERA_INFO, camera=camera) if self.calibration else None
        )
        self.status_pub = node.publisher(registry.CAMERA_STATUS, camera=camera)
        self.source = make_source(config, factory, clock)
        self.slot = FrameSlot(name="captured frames", clock=clock)
        self.reader: Reader | None = None
        self.published = 0
        self.dropped = 0
        self._taken = 0
        self._status_at = clock.monotonic()
        self._published_at_status = 0
        self._fps_measured = 0.0
        self._status_count = 0

    # ---- start / stop ----

    def start(self) -> None:
        """Open the source and start reading.

        A stream is opened by the reader (opening may block up to ``open_timeout``, and a stop
        must not wait for it); a device, a file or the pattern here, so that errors exit 2.

        Raises:
            SourceError: the device, file or pattern cannot be used (names it); a stream
                that is not up yet is not an error (the reader retries it).
        """
        opened = self.config.source_kind != "url"
        if opened:
            mode = self.source.open()
            log.info("%s: %s", self.source.description, mode)
            if self.config.source_kind == "device":
                c = self.config
                fmt = c.pixel_format or "(default format)"
                log.info("requested %dx%d %s @%g fps", c.width, c.height, fmt, c.fps)
        self.reader = Reader(
            self.source,
            self.config,
            self.slot,
            self.node.stop_event,
            opened=opened,
            clock=self.clock,
        )
        self.reader.start()

    def close(self) -> None:
        """Stop the reader. One blocked inside OpenCV (a stream being opened, up to
        ``open_timeout``) is not waited for beyond ``CLOSE_WAIT_S``: it is a daemon thread and
        the process exits without it."""
        self.node.stop()
        if self.reader is not None:
            self.reader.join(CLOSE_WAIT_S)
            if self.reader.is_alive():
                log.warning(
                    "the reader is still blocked in %s; exiting without it", self.source.description
                )
        log.info("%s", self.counters())

    # ---- loop ----

    def spin(self) -> None:
        """Publish frames until stopped or a file played once has ended.

        Raises:
            ValueError: the crop does not fit the frames (names both).
            CalibrationError: the calibration does not fit the frames.
        """
        while not self.node.stopping:
            self.spin_once(WAIT_S)
            self._maybe_status()
            reader = self.reader
            if reader is not None and not reader.is_alive() and self.slot.count <= self._taken:
                break
        self.publish_status()

    def spin_once(self, timeout: float) -> bool:
        """Publish the newest frame if one came within ``timeout`` s; True if one did."""
        got = self.slot.take(timeout, self._taken)
        if got is None:
            return False
        number, captured = got
        self.dropped += number - self._taken - 1
        self._taken = number
        self.publish(captured)
        return True

    def publish(self, captured: Captured) -> None:
        """Transform and publish one frame (raw, JPEG, CameraInfo as configured/watched)."""
        frame = self.transform.apply(captured.frame)
        stamp, camera, seq = captured.stamp, self.config.camera, captured.number
        if self.raw is not None and self.raw.watched():
            self.raw.put(bgr_to_image(frame, stamp, camera, seq))
        if self.config.jpeg or self.jpeg.watched():
            self.jpeg.put(bgr_to_jpeg(frame, stamp, camera, seq, self.config.jpeg_quality))
        if self.info is not None:
            header = Header(stamp=stamp, frame_id=camera, seq=seq)
            self.info.put(self.camera_info(captured.frame, header))
        self.published += 1
        if self.published == 1:
            height, width = frame.shape[:2]
            log.info("publishing %dx%d frames on %s", width, height, self.config.camera)
            self.node.announce()

    def camera_info(self, captured: np.ndarray, header: Header) -> CameraInfo:
        """The CameraInfo of the published frame made from a ``captured`` frame.

        Raises:
            CalibrationError: the calibration is for another frame size than captured.
        """
        assert self.calibration is not None
        size = (captured.shape[1], captured.shape[0])
        if self._info_for is None or self._info_for[0] != size:
            cal = self.calibration
            if (cal.width, cal.height) != size:
                raise CalibrationError(
                    f"{self.config.calibration_file} is for {cal.width}x{cal.height} frames, "
                    f"the camera gives {size[0]}x{size[1]}"
                )
            self._info_for = (size, transformed(cal, self.transform))
        info = self._info_for[1]
        return CameraInfo(
            header=header,
            height=info.height,
            width=info.width,
            distortion_model=info.distortion_model,
            d=list(info.d),
            k=list(info.k),
            r=list(info.r),
            p=list(info.p),
        )

    # ---- status ----

    def status(self) -> CameraStatus:
        assert self.reader is not None
        stats = self.reader.stats
        return CameraStatus(
            header=Header(
                stamp=self.clock.time(), frame_id=self.config.camera, seq=self._status_count
            ),
            source=self.source.description,
            state=stats.state,
            width=stats.mode.width,
            height=stats.mode.height,
            fps=stats.mode.fps,
            pixel_format=stats.mode.pixel_format,
            fps_measured=self._fps_measured,
            frames_captured=stats.frames_captured,
            frames_published=self.published,
            frames_dropped=self.dropped,
            corrupt_frames=stats.corrupt_frames + stats.bad_frames,
            reconnects=stats.reconnects,
            open_failures=stats.open_failures,
            truncated=stats.truncated,
            last_error=stats.last_error,
        )

    def publish_status(self) -> None:
        if self.reader is not None:
            self.status_pub.put(self.status())
            self._status_count += 1

    def _maybe_status(self) -> None:
        now = self.clock.monotonic()
        elapsed = now - self._status_at
        if elapsed < self.config.status_period:
            return
        self._fps_measured = (self.published - self._published_at_status) / elapsed
        self._status_at, self._published_at_status = now, self.published
        self.publish_status()
        if self._status_count % LOG_EVERY == 0:
            log.info("%s", self.counters())

    def counters(self) -> str:
        if self.reader is None:
            return "not started"
        s = self.reader.stats
        return (
            f"{s.state}: captured={s.frames_captured} published={self.published} "
            f"dropped={self.dropped} corrupt={s.corrupt_frames + s.bad_frames} "
            f"reconnects={s.reconnects} open_failures={s.open_failures} truncated={s.truncated} "
            f"fps={self._fps_measured:.1f}"
        )


PORTS = Ports(
    "camera_victure",
    publishes=(
        registry.IMAGE_RAW,
        registry.IMAGE_COMPRESSED,
        registry.CAMERA_INFO,
        registry.CAMERA_STATUS,
    ),
)
"""What the camera publishes (:mod:`dronewrapper.runtime.ports`)."""


def run(node: NodeApi, config: Config, factory: Factory = opencv_factory) -> int:
    """The camera service (see the module doc). Exit 0 on a stop or the end of a file played
    once, 2 for a source or calibration that cannot be used, 1 when reading failed unexpectedly."""
    try:
        service = CameraService(node, config, factory)
        service.start()
    except (SourceError, CalibrationError) as exc:
        log.error("%s", exc)
        return 2
    try:
        service.spin()
    except (ValueError, CalibrationError) as exc:  # crop / calibration vs the real frames
        log.error("%s", exc)
        return 2
    finally:
        service.close()
    reader = service.reader
    return 1 if reader is not None and reader.failure is not None else 0
