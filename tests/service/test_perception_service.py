"""The perception service in-process on a real Zenoh router: frames in, Detections out."""

from __future__ import annotations

import threading
import time
from collections.abc import Iterator
from contextlib import contextmanager

import cv2
import numpy as np

from dronewrapper.msgs import CompressedImage, Detections, Header, Image, registry
from dronewrapper.runtime.config import load_config
from dronewrapper_perception.color_filter import RED
from dronewrapper_perception.config import Config
from dronewrapper_perception.detectors import ColorDetector
from dronewrapper_perception.frames import bgr_to_image
from dronewrapper_perception.node import PerceptionService
from dronewrapper_perception.pipeline import Pipeline
from support import client_node, wait_for


def red_disc_frame(cx: int = 200, cy: int = 150, r: int = 30) -> np.ndarray:
    img = np.full((240, 320, 3), (80, 120, 70), np.uint8)
    cv2.circle(img, (cx, cy), r, (0, 0, 230), -1)
    return img


def disc_msg(stamp: float, cx: int = 200, cy: int = 150) -> Image:
    return bgr_to_image(red_disc_frame(cx, cy), stamp, "cam_frontal")


@contextmanager
def running_service(router: str, pipeline_factory=None, **settings) -> Iterator:
    """A PerceptionService spinning in a thread, plus a camera/test node on the same router."""
    config = load_config(Config, data=settings)
    with client_node(router, name="perception") as pnode, client_node(router, name="cam") as cam:
        pipeline = pipeline_factory(config) if pipeline_factory else None
        service = PerceptionService(pnode, config, pipeline)
        received: list[tuple[float, Detections]] = []
        cam.subscribe(registry.DETECTIONS, lambda m: received.append((time.time(), m)))
        thread = threading.Thread(target=service.spin, daemon=True)
        thread.start()
        try:
            yield service, cam, received
        finally:
            pnode.stop()
            thread.join(10)
            assert not thread.is_alive()


def publish_until_received(pub, make_msg, received, count: int = 1, timeout: float = 20.0):
    """Publish frames every 50 ms until ``count`` detections arrived (discovery takes a moment)."""

    def done():
        if len(received) >= count:
            return True
        pub.put(make_msg())
        return False

    wait_for(done, timeout, interval=0.05, what=f"{count} Detections")


def test_raw_frames_give_detections_with_source_stamp(router):
    with running_service(router) as (service, cam, received):
        pub = cam.publisher(registry.IMAGE_RAW, camera="cam_frontal")
        publish_until_received(
            pub, lambda: bgr_to_image(red_disc_frame(), 1000.0, "cam_frontal"), received
        )
        stamp = 1700000000.25
        before = len(received)
        pub.put(bgr_to_image(red_disc_frame(100, 80), stamp, "cam_frontal"))
        wait_for(lambda: any(m.header.stamp == stamp for _, m in received[before:]), 10)
        msg = next(m for _, m in received[before:] if m.header.stamp == stamp)
        assert msg.header.frame_id == "cam_frontal"
        assert (msg.image_width, msg.image_height, msg.detector) == (320, 240, "color")
        target = msg.target()
        assert target is not None
        assert abs(target.bbox.center.position.x - 100) < 2
        assert abs(target.bbox.center.position.y - 80) < 2
        assert abs(target.circle_radius - 30) < 3
        assert service.stats.processed >= 2 and not service.stats.bad
        # the latency budget's timing fields (s): decode is part of the processing time
        assert 0.0 <= msg.decode_time <= msg.processing_time < 10.0
        assert 0.0 <= msg.queue_time < 10.0
        assert 0.0 < msg.receive_time - time.time() + 60.0 < 60.0  # Unix time, in the past


def test_bad_frames_are_counted_and_skipped(router):
    with running_service(router) as (service, cam, received):
        pub = cam.publisher(registry.IMAGE_RAW, camera="cam_frontal")
        publish_until_received(
            pub, lambda: bgr_to_image(red_disc_frame(), 1.0, "cam_frontal"), received
        )
        bad = [
            Image(
                header=Header(stamp=2.0), width=320, height=240, encoding="bgr8", data=b"\1" * 99
            ),
            Image(header=Header(stamp=3.0), width=4, height=4, encoding="yuv422", data=b"\1" * 32),
            Image(header=Header(stamp=4.0), width=320, height=240, encoding="bgr8", data=b""),
        ]
        for n, msg in enumerate(bad, start=1):  # one at a time, so the newest-frame policy
            pub.put(msg)  # keeps each
            wait_for(lambda n=n: sum(service.stats.bad.values()) >= n, 10, what=f"bad frame {n}")
        assert sum(service.stats.bad.values()) == 3
        assert dict(service.stats.bad) == {"bad_size": 1, "encoding": 1, "empty": 1}
        # the service keeps working after them
        good_stamp = 5.0
        pub.put(bgr_to_image(red_disc_frame(), good_stamp, "cam_frontal"))
        wait_for(lambda: any(m.header.stamp == good_stamp for _, m in received), 10)
        assert not any(m.header.stamp in (2.0, 3.0, 4.0) for _, m in received)


def test_compressed_frames_and_debug_image(router):
    with running_service(router, compressed=True, debug_image=True) as (service, cam, received):
        debug: list[CompressedImage] = []
        cam.subscribe(registry.DETECTIONS_DEBUG_IMAGE, debug.append)
        pub = cam.publisher(registry.IMAGE_COMPRESSED, camera="cam_frontal")
        jpeg = cv2.imencode(".jpg", red_disc_frame())[1].tobytes()

        def frame():
            return CompressedImage(header=Header(stamp=7.0, frame_id="cam_frontal"), data=jpeg)

        publish_until_received(pub, frame, received)
        assert received[0][1].target() is not None
        wait_for(lambda: debug, 10, what="debug image")
        shown = cv2.imdecode(np.frombuffer(debug[0].data, np.uint8), cv2.IMREAD_COLOR)
        assert shown.shape == (240, 320, 3) and debug[0].header.stamp == 7.0
        pub.put(CompressedImage(header=Header(stamp=8.0), data=b"garbage"))
        wait_for(lambda: service.stats.bad["undecodable"] == 1, 10)


class SlowDetector(ColorDetector):
    """The real colour detector, made slow (100 ms a frame) to outpace it with frames."""

    def detect(self, bgr):
        time.sleep(0.1)
        return super().detect(bgr)


def test_newest_frame_policy_keeps_latency_bounded(router):
    def slow_pipeline(config):
        return Pipeline(config, detector=SlowDetector(RED))

    with running_service(router, pipeline_factory=slow_pipeline) as (service, cam, received):
        pub = cam.publisher(registry.IMAGE_RAW, camera="cam_frontal")
        publish_until_received(
            pub, lambda: bgr_to_image(red_disc_frame(), time.time(), "c"), received
        )
        start_count = len(received)
        stats = service.stats
        received0, processed0, dropped0 = stats.received, stats.processed, stats.dropped
        sent = 0
        t_end = time.monotonic() + 3.0
        while time.monotonic() < t_end:  # ~100 frames/s for 3 s against ~10 frames/s processing
            pub.put(bgr_to_image(red_disc_frame(), time.time(), "cam_frontal"))
            sent += 1
            time.sleep(0.01)
        last_stamp = time.time()
        pub.put(bgr_to_image(red_disc_frame(), last_stamp, "cam_frontal"))
        wait_for(lambda: any(m.header.stamp == last_stamp for _, m in received), 10)
        latest = [(rx - m.header.stamp) for rx, m in received[start_count:]]
        # counted against the frames that reached the service (Zenoh may drop some on the way)
        arrived = stats.received - received0
        processed = stats.processed - processed0
        assert processed < arrived / 3, f"{processed} of {arrived} processed: queued, not dropped"
        assert stats.dropped - dropped0 > arrived / 2
        # With a queue the latency would grow with every frame (~10 frames/s processed of
        # 50-100/s sent: the last one would wait over 10 s). Here each frame waits at most ~2
        # frames (about 0.15 s); the median ignores a rare stall of a busy machine.
        median = sorted(latest)[len(latest) // 2]
        assert median < 0.5, f"median latency {median:.2f} s: {latest}"
        last = next(rx - m.header.stamp for rx, m in received if m.header.stamp == last_stamp)
        assert last < 3.0, f"the last frame waited {last:.2f} s"


class FragileDetector(ColorDetector):
    """The real colour detector, made to fail on an all-white frame."""

    def detect(self, bgr):
        if bgr.min() == 255:
            raise RuntimeError("detector failed on this frame")
        return super().detect(bgr)


def test_a_detector_failure_skips_the_frame_not_the_service(router):
    def fragile(config):
        return Pipeline(config, detector=FragileDetector(RED))

    with running_service(router, pipeline_factory=fragile) as (service, cam, received):
        pub = cam.publisher(registry.IMAGE_RAW, camera="cam_frontal")
        publish_until_received(pub, lambda: disc_msg(1.0), received)
        white = np.full((240, 320, 3), 255, np.uint8)
        pub.put(bgr_to_image(white, 2.0, "cam_frontal"))
        wait_for(lambda: service.stats.bad["processing_error"] == 1, 10, what="counted failure")
        pub.put(disc_msg(3.0))
        wait_for(lambda: any(m.header.stamp == 3.0 for _, m in received), 10)
        assert not any(m.header.stamp == 2.0 for _, m in received)
