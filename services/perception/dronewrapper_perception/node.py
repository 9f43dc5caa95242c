"""The perception process: camera frames in, Detections out, always on the newest frame.

A Zenoh subscriber stores each decoded camera message in a one-slot holder (the runtime's
``Latest``);
the main loop takes the newest one and skips any that arrived meanwhile (counted as dropped), so a
slow detector never builds a queue and latency never grows. Each processed frame gives one
Detections message carrying the frame's own stamp. Bad frames are counted by reason, logged
(rate-limited) and skipped.
"""

from __future__ import annotations

import logging
import math
import time
from collections import Counter
from dataclasses import dataclass, field
from typing import Any

import msgspec

from dronewrapper.images import BadFrame, compressed_to_bgr, image_to_bgr
from dronewrapper.msgs import CompressedImage, Header, Image, registry
from dronewrapper.msgs.registry import Topic
from dronewrapper.runtime import Latest
from dronewrapper.runtime.contract import NodeApi
from dronewrapper.runtime.ports import Ports
from dronewrapper_perception.config import Config
from dronewrapper_perception.model_file import ModelFileError
from dronewrapper_perception.pipeline import Pipeline, annotate, encode_jpeg, to_message
from dronewrapper_perception.rate_cap import FrameRateCap

log = logging.getLogger("perception")

WAIT_S = 0.5
"""Longest wait for a frame (s), so a stop request is seen promptly."""

BAD_LOG_PERIOD_S = 5.0


@dataclass
class Stats:
    """Counters of the frame loop."""

    received: int = 0
    processed: int = 0
    dropped: int = 0
    skipped: int = 0
    """Frames left out by ``max_rate_hz``."""
    bad: Counter[str] = field(default_factory=Counter)

    def line(self) -> str:
        bad = ", ".join(f"{k}={v}" for k, v in sorted(self.bad.items())) or "0"
        return (
            f"frames received={self.received} processed={self.processed} "
            f"dropped(stale)={self.dropped} skipped(rate cap)={self.skipped} bad: {bad}"
        )


def frames_topic(compressed: bool) -> Topic[Any]:
    """The topic of the camera's frames: JPEG (``compressed``) or raw."""
    return registry.IMAGE_COMPRESSED if compressed else registry.IMAGE_RAW


PORTS = Ports(
    "perception",
    publishes=(registry.DETECTIONS, registry.DETECTIONS_DEBUG_IMAGE),
    subscribes=(registry.IMAGE_RAW, registry.IMAGE_COMPRESSED),  # as ``compressed`` says
)
"""What perception publishes and subscribes to (:mod:`dronewrapper.runtime.ports`)."""


class PerceptionService:
    """Subscribes to the camera, runs the pipeline on the newest frame, publishes Detections.

    Raises (at construction):
        ModelFileError: the configured model file is missing or fails its checksum.
    """

    def __init__(self, node: NodeApi, config: Config, pipeline: Pipeline | None = None) -> None:
        self.node = node
        self.config = config
        self.pipeline = pipeline or Pipeline(config)
        self.stats = Stats()
        self.topic = frames_topic(config.compressed)
        self.clock = node.clock
        self.frames: Latest[tuple[float, Image | CompressedImage]] = Latest(
            name="camera frames", clock=node.clock
        )
        node.subscribe(self.topic, self._on_frame, camera=config.camera)
        self.publisher = node.publisher(registry.DETECTIONS)
        self.debug = node.publisher(registry.DETECTIONS_DEBUG_IMAGE) if config.debug_image else None
        self.rate_cap = FrameRateCap(config.max_rate_hz)
        self._seen = 0
        self._last_bad_log: dict[str, float] = {}

    def _on_frame(self, msg: Image | CompressedImage) -> None:
        """A frame from the camera: kept, with when it came (node clock), for the spin."""
        self.frames.update((self.clock.time(), msg))

    def spin(self) -> None:
        """Process frames until the node is asked to stop."""
        last_stats = self.clock.monotonic()
        while not self.node.stopping:
            self.spin_once(WAIT_S)
            now = self.clock.monotonic()
            if self.config.stats_period_s > 0 and now - last_stats >= self.config.stats_period_s:
                last_stats = now
                log.info("%s", self.stats.line())

    def spin_once(self, timeout: float) -> bool:
        """Wait up to ``timeout`` s for a frame newer than the last one; process the newest.

        Returns True if a frame was taken (processed, skipped by the rate cap or rejected as
        bad).
        """
        taken = self.frames.take(timeout, newer_than=self._seen)
        if taken is None:
            return False
        count, (arrival, msg) = taken
        self.stats.received = count
        self.stats.dropped += max(0, count - self._seen - 1)
        self._seen = count
        stamp = msg.header.stamp
        if math.isfinite(stamp) and not self.rate_cap.admit(stamp):
            self.stats.skipped += 1
            return True
        self.handle(msg, received=arrival)
        return True

    def handle(self, msg: Image | CompressedImage, received: float = 0.0) -> None:
        """Decode, process and publish one frame (bad frames are counted and skipped);
        ``received`` (Unix time the frame arrived, 0 = now) and the wait since are reported in
        the Detections."""
        now = self.clock.time()
        received = received or now
        queue_time = now - received
        start = time.perf_counter()  # the decode's CPU cost, not the service's time
        try:
            if isinstance(msg, CompressedImage):
                bgr = compressed_to_bgr(msg)
            else:
                bgr = image_to_bgr(msg, copy=False)
        except BadFrame as exc:
            self._bad(exc)
            return
        decode_time = time.perf_counter() - start
        header = msg.header
        if not (math.isfinite(header.stamp) and header.stamp >= 0.0):  # it becomes the PIDs' time
            self._bad(BadFrame("bad_stamp", f"header.stamp must be finite, got {header.stamp!r}"))
            return
        frame_id = header.frame_id or self.config.camera
        try:
            result = self.pipeline.process(bgr, header.stamp)
        except Exception as exc:  # a detector failing on one frame must not end the loop
            self._bad(BadFrame("processing_error", f"{type(exc).__name__}: {exc}"))
            return
        self.stats.processed += 1
        detections = to_message(
            result,
            stamp=header.stamp,
            frame_id=frame_id,
            detector=self.pipeline.detector_name,
            seq=self.stats.processed,
            extra_time=decode_time,
        )
        self.publisher.put(
            msgspec.structs.replace(
                detections,
                receive_time=received,
                queue_time=max(0.0, queue_time),
                decode_time=decode_time,
            )
        )
        if self.debug is not None:
            jpeg = encode_jpeg(annotate(bgr, result), self.config.debug_jpeg_quality)
            self.debug.put(
                CompressedImage(
                    header=Header(stamp=header.stamp, frame_id=frame_id),
                    format="jpeg",
                    data=memoryview(jpeg),
                )
            )

    def _bad(self, exc: BadFrame) -> None:
        self.stats.bad[exc.reason] += 1
        now = self.clock.monotonic()
        if now - self._last_bad_log.get(exc.reason, -1e9) >= BAD_LOG_PERIOD_S:
            self._last_bad_log[exc.reason] = now
            log.warning(
                "bad frame skipped (%d %s so far): %s", self.stats.bad[exc.reason], exc.reason, exc
            )


def run(node: NodeApi, config: Config) -> int:
    """Serve perception until stopped. Returns 2 when the detector cannot be built."""
    try:
        service = PerceptionService(node, config)
    except (ModelFileError, ValueError) as exc:
        log.error("cannot start the %s detector: %s", config.detector_kind(), exc)
        return 2
    if config.detector == "person" and not config.model_path:
        log.info("detector=person without model_path: using OpenCV's HOG people detector")
    service.pipeline.warm_up()
    log.info(
        "perception ready: %s detector, %s tracker, on %s -> %s",
        service.pipeline.detector_name,
        config.tracker,
        service.topic.key(node.ns, camera=config.camera),
        service.publisher.key,
    )
    node.announce()
    service.spin()
    log.info("stopping: %s", service.stats.line())
    return 0
