"""The stop-gap USB camera publisher (real-hardware graph), fed from a real video file."""

from __future__ import annotations

import threading

import numpy as np

from dronewrapper.msgs import registry
from dronewrapper.runtime.config import load_config
from dronewrapper_compose.usb_camera import Config, run
from support import ASSETS, client_node, wait_for


def test_publishes_stamped_bgr_frames_and_jpeg(router):
    config = load_config(
        Config, None, [f"device={ASSETS / 'video' / 'vtest.avi'}", "fps=15", "compressed=true"]
    )
    tester = client_node(router, name="tester")
    frames = tester.latest(registry.IMAGE_RAW, camera="cam_frontal")
    jpegs = tester.latest(registry.IMAGE_COMPRESSED, camera="cam_frontal")
    cam = client_node(router, name="usb_camera")
    result: list[int] = []
    thread = threading.Thread(target=lambda: result.append(run(cam, config)), daemon=True)
    thread.start()
    try:
        wait_for(lambda: frames.count >= 5 and jpegs.count >= 5, 20, what="frames")
        img = frames.value
        assert img.encoding == "bgr8" and img.step == img.width * 3
        assert len(img.data) == img.width * img.height * 3
        pixels = np.frombuffer(img.data, np.uint8).reshape(img.height, img.width, 3)
        assert pixels.std() > 5  # a real picture, not a blank buffer
        assert img.header.stamp > 1e9 and img.header.frame_id == "cam_frontal"
        assert jpegs.value.data[:2] == b"\xff\xd8"
    finally:
        cam.stop()
        thread.join(10)
        cam.close()
        tester.close()
    assert result == [0]


def test_missing_device_gives_up(router):
    config = load_config(Config, None, ["device=/nonexistent/video.avi", "open_timeout=1"])
    cam = client_node(router, name="usb_camera")
    try:
        assert run(cam, config) == 1
    finally:
        cam.close()
