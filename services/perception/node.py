"""The perception process: camera frames in, Detections out, always on the newest frame.

A Zenoh subscriber stores each decoded camera message in a one-slot holder (``Latest``); the
main loop takes the newest one, skips any that arrived meanwhile (counted as dropped), so a slow
detector never builds a queue and latency never grows. Each processed frame gives one
Detections message carrying the frame's own stamp. Bad frames are counted by reason, logged
(rate-limited) and skipped.
"""

from __future__ import annotations

import logging
import time
from collections import Counter
from dataclasses import dataclass, field

from dronewrapper.msgs import CompressedImage, Header, registry
from dronewrapper.runtime import Node
from dronewrapper_perception.config import Config
from dronewrapper_perception.frames import BadFrame, compressed_to_bgr, image_to_bgr
from dronewrapper_perception.model_file import ModelFileError
from dronewrapper_perception.pipeline import Pipeline, annotate, encode_jpeg, to_message

log = logging.getLogger("perception")

WAIT_S = 0.5  # bounded wait for a frame, so a stop request is seen promptly


@dataclass
class Stats:
    """Counters of the frame loop."""

    received: int = 0
    processed: int = 0
    dropped: int = 0
    bad: Counter[str] = field(default_factory=Counter)

    def line(self) -> str:
        bad = ", ".join(f"{k}={v}" for k, v in sorted(self.bad.items())) or "0"
        return (
            f"frames received={self.received} processed={self.processed} "
            f"dropped(stale)={self.dropped} bad: {bad}"
        )


def run(node: Node, config: Config) -> int:
    """Serve perception until stopped. Returns 2 when the detector cannot be built."""
    try:
        pipeline = Pipeline(config)
    except (ModelFileError, ValueError) as exc:
        log.error("cannot start the %s detector: %s", config.detector_kind(), exc)
        return 2
    pipeline.warm_up()
    topic = registry.IMAGE_COMPRESSED if config.compressed else registry.IMAGE_RAW
    frames = node.latest(topic, camera=config.camera)
    publisher = node.publisher(registry.DETECTIONS)
    debug = node.publisher(registry.DETECTIONS_DEBUG_IMAGE) if config.debug_image else None
    log.info(
        "perception ready: %s detector, %s tracker, on %s -> %s",
        pipeline.detector_name,
        config.tracker,
        topic.key(node.ns, camera=config.camera),
        publisher.key,
    )
    node.announce()
    stats = Stats()
    seen = 0
    last_stats = time.monotonic()
    last_bad_log: dict[str, float] = {}
    while not node.stopping:
        try:
            msg = frames.wait(WAIT_S, newer_than=seen)
        except TimeoutError:
            msg = None
        if msg is not None:
            count = frames.count
            stats.received = count
            stats.dropped += max(0, count - seen - 1)
            seen = count
            _process(node, config, pipeline, msg, publisher, debug, stats, last_bad_log)
        now = time.monotonic()
        if config.stats_period_s > 0 and now - last_stats >= config.stats_period_s:
            last_stats = now
            log.info("%s", stats.line())
    log.info("stopping: %s", stats.line())
    return 0


def _process(node, config, pipeline, msg, publisher, debug, stats, last_bad_log) -> None:
    start = time.perf_counter()
    try:
        bgr = compressed_to_bgr(msg) if isinstance(msg, CompressedImage) else image_to_bgr(msg)
    except BadFrame as exc:
        stats.bad[exc.reason] += 1
        now = time.monotonic()
        if now - last_bad_log.get(exc.reason, -1e9) >= 5.0:
            last_bad_log[exc.reason] = now
            log.warning(
                "bad frame skipped (%d %s so far): %s", stats.bad[exc.reason], exc.reason, exc
            )
        return
    decode_time = time.perf_counter() - start
    header: Header = msg.header
    result = pipeline.process(bgr, header.stamp)
    stats.processed += 1
    publisher.put(
        to_message(
            result,
            stamp=header.stamp,
            frame_id=header.frame_id or config.camera,
            detector=pipeline.detector_name,
            seq=stats.processed,
            extra_time=decode_time,
        )
    )
    if debug is not None:
        jpeg = encode_jpeg(annotate(bgr, result), config.debug_jpeg_quality)
        debug.put(
            CompressedImage(
                header=Header(stamp=header.stamp, frame_id=header.frame_id or config.camera),
                format="jpeg",
                data=jpeg,
            )
        )
