"""The perception service in-process: frames in, Detections out.

Its logic runs on the fake bus in bus time (frames delivered when scheduled, the newest-frame
policy judged by message stamps); one test on a real Zenoh router proves the wiring."""

from __future__ import annotations

import math
import threading
import time
from collections.abc import Iterator
from contextlib import contextmanager

import cv2
import numpy as np

from dronewrapper.images import bgr_to_image
from dronewrapper.msgs import CompressedImage, Detections, Header, Image, registry
from dronewrapper.runtime.config import load_config
from dronewrapper.runtime.fake import FakeBus, FakeNode
from dronewrapper_perception.color_filter import RED
from dronewrapper_perception.config import Config
from dronewrapper_perception.detectors import ColorDetector
from dronewrapper_perception.node import PerceptionService
from dronewrapper_perception.pipeline import Pipeline
from support import client_node, wait_for


def red_disc_frame(cx: int = 200, cy: int = 150, r: int = 30) -> np.ndarray:
    img = np.full((240, 320, 3), (80, 120, 70), np.uint8)
    cv2.circle(img, (cx, cy), r, (0, 0, 230), -1)
    return img


def disc_msg(stamp: float, cx: int = 200, cy: int = 150) -> Image:
    return bgr_to_image(red_disc_frame(cx, cy), stamp, "cam_frontal")


RAW = registry.IMAGE_RAW.key("drone", camera="cam_frontal")
COMPRESSED = registry.IMAGE_COMPRESSED.key("drone", camera="cam_frontal")


def fake_service(pipeline_factory=None, **settings):
    """A PerceptionService on the fake bus: (service, bus, the Detections published so far)."""
    config = load_config(Config, data=settings)
    bus = FakeBus(start=0.0)
    pipeline = pipeline_factory(config) if pipeline_factory else None
    service = PerceptionService(FakeNode("perception", bus), config, pipeline)

    def received() -> list[Detections]:
        return [out.msg for out in bus.published[registry.DETECTIONS.key("drone")]]

    return service, bus, received


def deliver(service: PerceptionService, bus: FakeBus) -> None:
    """Deliver every scheduled frame, then let the service take the newest one."""
    while bus.step():
        pass
    service.spin_once(0.0)


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


def test_bad_frames_are_counted_and_skipped():
    service, bus, received = fake_service()
    bad = [
        Image(header=Header(stamp=2.0), width=320, height=240, encoding="bgr8", data=b"\1" * 99),
        Image(header=Header(stamp=3.0), width=4, height=4, encoding="yuv422", data=b"\1" * 32),
        Image(header=Header(stamp=4.0), width=320, height=240, encoding="bgr8", data=b""),
        Image(header=Header(stamp=math.nan), width=4, height=2, encoding="bgr8", data=b"\1" * 24),
    ]
    for n, msg in enumerate(bad, start=1):  # one at a time, so the newest-frame policy keeps each
        bus.schedule(float(n), RAW, msg)
        deliver(service, bus)
    assert dict(service.stats.bad) == {"bad_size": 1, "encoding": 1, "empty": 1, "bad_stamp": 1}
    # the service keeps working after them
    bus.schedule(5.0, RAW, disc_msg(5.0))
    deliver(service, bus)
    assert [m.header.stamp for m in received()] == [5.0]
    assert service.stats.processed == 1 and service.stats.received == 5


def test_max_rate_hz_detects_on_frames_of_that_rate_by_their_stamps():
    """A 30 fps camera, perception capped at 10 fps: one frame in three is processed, chosen by
    the frames' stamps (so the same ones on any machine), the others counted as skipped."""
    service, bus, received = fake_service(max_rate_hz=10.0)
    for n in range(30):
        bus.schedule(n / 30, RAW, disc_msg(n / 30))
        deliver(service, bus)
    stamps = [m.header.stamp for m in received()]
    assert stamps == [n / 30 for n in range(0, 30, 3)]
    assert service.stats.skipped == 20 and service.stats.processed == 10


def test_compressed_frames_and_debug_image():
    service, bus, received = fake_service(compressed=True, debug_image=True)
    jpeg = cv2.imencode(".jpg", red_disc_frame())[1].tobytes()
    bus.schedule(7.0, COMPRESSED, CompressedImage(header=Header(stamp=7.0), data=jpeg))
    deliver(service, bus)
    (msg,) = received()
    assert msg.target() is not None and msg.header.frame_id == "cam_frontal"
    (debug,) = bus.published[registry.DETECTIONS_DEBUG_IMAGE.key("drone")]
    shown = cv2.imdecode(np.frombuffer(debug.msg.data, np.uint8), cv2.IMREAD_COLOR)
    assert shown.shape == (240, 320, 3) and debug.msg.header.stamp == 7.0
    bus.schedule(8.0, COMPRESSED, CompressedImage(header=Header(stamp=8.0), data=b"garbage"))
    deliver(service, bus)
    assert service.stats.bad["undecodable"] == 1 and len(received()) == 1


def test_newest_frame_policy_keeps_latency_bounded():
    """Frames at 100 Hz against 100 ms of processing each (in bus time): every processed frame
    is the newest, the others are dropped, and no frame waits more than one processing time
    plus one frame period, where a queue would age frame n by n x 90 ms."""
    service, bus, received = fake_service()
    period, busy = 0.01, 0.1
    frames = 300  # 3 s
    for n in range(frames):
        bus.schedule(n * period, RAW, disc_msg(n * period))
    bus.step()
    while service.spin_once(0.0):  # processing takes ``busy``: frames arrive meanwhile
        bus.run_until(bus.clock() + busy)
    published = bus.published[registry.DETECTIONS.key("drone")]
    assert len(published) == service.stats.processed
    assert frames / 12 < service.stats.processed < frames / 8  # about one in ten processed
    assert service.stats.processed + service.stats.dropped == service.stats.received == frames
    latency = [out.time - out.msg.header.stamp for out in published]
    assert max(latency) <= period + 1e-9, latency  # taken the moment it was free: the newest
    assert published[-1].msg.header.stamp == (frames - 1) * period  # the last frame is not lost
    assert all(m.target() is not None for m in received())


class FragileDetector(ColorDetector):
    """The real colour detector, made to fail on an all-white frame."""

    def detect(self, bgr):
        if bgr.min() == 255:
            raise RuntimeError("detector failed on this frame")
        return super().detect(bgr)


def test_a_detector_failure_skips_the_frame_not_the_service():
    service, bus, received = fake_service(
        pipeline_factory=lambda config: Pipeline(config, detector=FragileDetector(RED))
    )
    white = np.full((240, 320, 3), 255, np.uint8)
    for stamp, msg in ((1.0, disc_msg(1.0)), (2.0, bgr_to_image(white, 2.0, "cam_frontal"))):
        bus.schedule(stamp, RAW, msg)
        deliver(service, bus)
    assert service.stats.bad["processing_error"] == 1
    bus.schedule(3.0, RAW, disc_msg(3.0))
    deliver(service, bus)
    assert [m.header.stamp for m in received()] == [1.0, 3.0]
