"""The perception service in-process on a real Zenoh router: the wiring (frames in, Detections
out, the source stamp kept). Its logic runs on the fake bus in
tests/service/test_perception_service.py."""

from __future__ import annotations

import threading
import time
from collections.abc import Iterator
from contextlib import contextmanager

from perception_frames import red_disc_frame

from dronewrapper.images import bgr_to_image
from dronewrapper.msgs import Detections, registry
from dronewrapper.runtime.config import load_config
from dronewrapper_perception.config import Config
from dronewrapper_perception.node import PerceptionService
from support import client_node, wait_for


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
