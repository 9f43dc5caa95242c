"""The perception process (``python -m dronewrapper_perception``) on a real loopback router."""

from __future__ import annotations

import time
from pathlib import Path

import cv2
import pytest

from dronewrapper.images import bgr_to_image
from dronewrapper.msgs import Detections, registry
from support import ASSETS, YOLOX_NANO, client_node, python_module, wait_for

pytestmark = pytest.mark.integration


def spawn_yolox(spawn, router: str, model: Path, *args: str):
    """The perception process with the YOLOX detector on ``model``, connected to ``router``."""
    command = python_module(
        "dronewrapper_perception",
        *("--connect", router, "--set", "detector=yolox", "--set", f"model_path={model}", *args),
    )
    return spawn(command, "perception")


def test_yolox_process_detects_people_and_stops_cleanly(router, spawn):
    proc = spawn_yolox(spawn, router, YOLOX_NANO, "--set", "threads=1")
    frame = cv2.imread(str(ASSETS / "images" / "basketball1.png"))
    with client_node(router) as node:
        received: list[Detections] = []
        node.subscribe(registry.DETECTIONS, received.append)
        pub = node.publisher(registry.IMAGE_RAW, camera="cam_frontal")
        stamp = 1700000123.5

        def answered():
            assert proc.alive(), proc.output()
            if any(m.header.stamp == stamp for m in received):
                return True
            pub.put(bgr_to_image(frame, stamp, "cam_frontal"))
            return False

        wait_for(answered, 60, interval=0.3, what="detections from the perception process")
        msg = next(m for m in received if m.header.stamp == stamp)
    assert msg.detector == "yolox" and (msg.image_width, msg.image_height) == (640, 480)
    assert len(msg.detections) == 2
    assert {d.results[0].hypothesis.class_id for d in msg.detections} == {"person"}
    assert msg.target() is not None
    assert proc.stop() == 0
    assert "perception ready" in proc.output()


def test_missing_model_is_a_clear_error_at_start(router, spawn, tmp_path):
    missing = tmp_path / "nowhere.onnx"
    proc = spawn_yolox(spawn, router, missing)
    deadline = time.monotonic() + 60
    while proc.alive() and time.monotonic() < deadline:
        time.sleep(0.1)
    assert proc.stop() == 2
    assert "does not exist" in proc.output() and "yolox_nano.onnx" in proc.output()


def test_bad_config_exits_2(router, spawn):
    proc = spawn(
        python_module("dronewrapper_perception", "--connect", router, "--set", "detectr=hog"),
        "perception",
    )
    wait_for(lambda: not proc.alive(), 60, what="exit on a bad config")
    assert proc.stop() == 2
    assert "detectr" in proc.output()
