"""The perception service in-process: frames in, Detections out.

Its logic runs on the fake bus in bus time (frames delivered when scheduled, the newest-frame
policy judged by message stamps); tests/integration/test_perception_router.py proves the wiring
on a real Zenoh router."""

from __future__ import annotations

import math

import cv2
import numpy as np
from perception_frames import disc_msg, red_disc_frame

from dronewrapper.images import bgr_to_image
from dronewrapper.msgs import CompressedImage, Detections, Header, Image, registry
from dronewrapper.runtime.config import load_config
from dronewrapper.runtime.fake import FakeBus, FakeNode
from dronewrapper_perception.color_filter import RED
from dronewrapper_perception.config import Config
from dronewrapper_perception.detectors import ColorDetector
from dronewrapper_perception.node import PORTS, PerceptionService
from dronewrapper_perception.pipeline import Pipeline

RAW = registry.IMAGE_RAW.key("drone", camera="cam_frontal")
COMPRESSED = registry.IMAGE_COMPRESSED.key("drone", camera="cam_frontal")


def fake_service(pipeline_factory=None, **settings):
    """A PerceptionService on the fake bus: (service, bus, the Detections published so far)."""
    config = load_config(Config, data=settings)
    bus = FakeBus(start=0.0)
    pipeline = pipeline_factory(config) if pipeline_factory else None
    service = PerceptionService(FakeNode("perception", bus, ports=PORTS), config, pipeline)

    def received() -> list[Detections]:
        return [out.msg for out in bus.published[registry.DETECTIONS.key("drone")]]

    return service, bus, received


def deliver(service: PerceptionService, bus: FakeBus) -> None:
    """Deliver every scheduled frame, then let the service take the newest one."""
    while bus.step():
        pass
    service.spin_once(0.0)


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
