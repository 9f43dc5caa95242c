"""The camera_victure service in this process, on the fake bus: a real video file, the test
pattern, truncated and damaged files, calibration, and start-up errors (a fake V4L2 capture
stands in for a device). The same service on a real Zenoh router (the wiring):
tests/integration/test_camera_victure_router.py."""

from __future__ import annotations

import random
import time

import numpy as np
import pytest
from camera_fake import EXPOSURE_AGE_S, FakeCapture
from camera_running import CALIBRATION, VIDEO, Running

from dronewrapper.images import compressed_to_bgr, image_to_bgr
from dronewrapper.msgs import registry
from dronewrapper_camera_victure.calibration import load_calibration, transformed
from dronewrapper_camera_victure.node import transform_of
from dronewrapper_camera_victure.pattern import read_counter
from support import wait_for


def test_a_file_played_once_as_fast_as_possible_loses_no_frame():
    overrides = [f"source={VIDEO}", "loop=false", "realtime=false", "resize=[192,144]"]
    with Running(overrides) as cam:
        wait_for(lambda: cam.result, 60, what="the end of the file")
        status = cam.wait_status(lambda s: s.state == "ended", 5, "the final status")
    assert cam.result == [0]
    # every frame published, in order
    assert [m.header.seq for m in cam.raw] == list(range(795))
    assert (cam.raw[0].width, cam.raw[0].height) == (192, 144)
    assert status.frames_captured == status.frames_published == 795
    assert status.frames_dropped == 0 and status.truncated == 0


def test_pattern_counter_flip_rotate_and_status():
    overrides = ["source=pattern", "fps=30", "rotate=180", "width=320", "height=240", "jpeg=true"]
    with Running(overrides) as cam:
        wait_for(lambda: len(cam.raw) >= 20, 20, what="pattern frames")
        status = cam.wait_status(lambda s: s.frames_published >= 20, 10, "status")
    frames = [image_to_bgr(m) for m in cam.raw]
    counters = [read_counter(np.rot90(f, 2)) for f in frames]  # undo the rotation
    assert counters == [m.header.seq for m in cam.raw]  # the picture is the frame it says
    assert counters == sorted(set(counters))
    assert read_counter(frames[-1]) != counters[-1] or counters[-1] == 0  # it was rotated
    assert read_counter(np.rot90(compressed_to_bgr(cam.jpeg.value), 2)) == (
        cam.jpeg.value.header.seq
    )
    assert status.state == "streaming" and status.source == "pattern"
    assert (status.width, status.height) == (320, 240)
    assert 0 < status.fps_measured < 45  # paced at 30 fps, never in bursts
    assert cam.result == [0]


def test_camera_info_follows_the_published_frame():
    overrides = [
        "source=pattern",
        "width=640",
        "height=480",
        f"calibration_file={CALIBRATION}",
        "rotate=90",
        "crop=[0,80,480,480]",
        "resize=[240,240]",
    ]
    with Running(overrides) as cam:
        wait_for(lambda: cam.info.count >= 3 and cam.raw, 20, what="camera_info")
        info, img = cam.info.value, cam.raw[-1]
    expect = transformed(load_calibration(CALIBRATION), transform_of(cam.config))
    assert (info.width, info.height) == (img.width, img.height) == (240, 240)
    assert info.k == pytest.approx(list(expect.k)) and info.d == pytest.approx(list(expect.d))
    assert info.header.frame_id == "cam_frontal" and info.header.stamp > 1e9


def _damaged(tmp_path, name: str, transform) -> str:
    data = bytearray(VIDEO.read_bytes())
    out = tmp_path / name
    out.write_bytes(transform(data))
    return str(out)


def test_a_truncated_file_is_counted_and_looped(tmp_path):
    path = _damaged(tmp_path, "truncated.avi", lambda d: d[: len(d) // 20])  # about 40 frames
    with Running([f"source={path}", "realtime=false", "resize=[192,144]"]) as cam:
        status = cam.wait_status(lambda s: s.truncated >= 2, 30, "two truncated passes")
        assert cam.thread.is_alive()
    assert status.frames_published >= 2 * 30
    assert "ended at frame" in status.last_error and "of 795" in status.last_error


def test_a_corrupt_file_is_survived(tmp_path):
    def corrupt(data: bytearray) -> bytes:
        rng = random.Random(1)
        for _ in range(200):
            at = rng.randrange(20_000, len(data) - 100)
            data[at : at + 50] = rng.randbytes(50)
        return bytes(data)

    path = _damaged(tmp_path, "corrupt.avi", corrupt)
    overrides = [f"source={path}", "realtime=false", "loop=false", "resize=[192,144]"]
    with Running(overrides) as cam:
        wait_for(lambda: cam.result, 60, what="the end of the damaged file")
        status = cam.wait_status(lambda s: s.state == "ended", 5, "the final status")
    assert cam.result == [0]
    assert status.frames_published > 700  # damaged frames decode with damage, or are skipped
    assert status.frames_published == len(cam.raw)


@pytest.mark.parametrize(
    ("overrides", "factory", "message"),
    [
        (["source=/nonexistent/video.avi"], None, "no video file /nonexistent/video.avi"),
        (["source=/dev/video97"], None, "no camera device /dev/video97"),
        (["source=pattern", "calibration_file=/nonexistent/cal.yaml"], None, "cal.yaml"),
        (
            ["source=pattern", f"calibration_file={CALIBRATION}", "width=320", "height=240"],
            None,
            "is for 640x480 frames, the camera gives 320x240",
        ),
        (["source=pattern", "crop=[0,0,700,10]"], None, "crop [0, 0, 700, 10] does not fit"),
        (["source=pattern", "width=40", "height=30"], None, "test pattern 40x30 too small"),
    ],
)
def test_start_up_errors_exit_2_naming_the_cause(caplog, overrides, factory, message):
    with Running([*overrides, "open_timeout=1"], factory) as cam:
        wait_for(lambda: cam.result, 15, what="exit")
    assert cam.result == [2]
    assert message in caplog.text


def _device_node(overrides, cap, monkeypatch):
    """The service on a fake V4L2 capture posing as /dev/video0."""
    from dronewrapper_camera_victure import sources

    monkeypatch.setattr(sources, "check_device_present", lambda path: None)
    return Running(["source=/dev/video0", *overrides], lambda *a: cap)


def test_device_unsupported_mode_exits_2(caplog, monkeypatch):
    cap = FakeCapture()
    with _device_node(["width=1024", "height=768", "pixel_format=MJPG"], cap, monkeypatch) as c:
        wait_for(lambda: c.result, 15, what="exit")
    assert c.result == [2]
    assert "camera /dev/video0 does not support size 1024x768 (got 1280x720)" in caplog.text
    assert cap.released


def test_device_busy_exits_2(caplog, monkeypatch):
    cap = FakeCapture(busy=True)
    with _device_node(["open_timeout=0.5"], cap, monkeypatch) as c:
        wait_for(lambda: c.result, 15, what="exit")
    assert c.result == [2]
    assert "camera /dev/video0 gives no frames within 0.5 s (busy" in caplog.text


def test_device_mode_granted_and_driver_stamps(monkeypatch):
    cap = FakeCapture()
    overrides = ["width=1280", "height=720", "pixel_format=YUYV", "fps=30"]
    with _device_node(overrides, cap, monkeypatch) as c:
        status = c.wait_status(lambda s: s.frames_published >= 3, 20, "device frames")
        img = c.raw[-1]
    assert (status.width, status.height, status.pixel_format) == (1280, 720, "YUYV")
    assert status.fps == 10.0  # what the device granted, reported
    assert (img.width, img.height) == (1280, 720)
    # the stamp is the driver's timestamp (50 ms before the read), not the read time
    read_number = int(image_to_bgr(img)[0, 0, 0])  # the fake fills frame n with n % 256
    read_wall = cap.read_walls[read_number]
    assert img.header.stamp == pytest.approx(read_wall - EXPOSURE_AGE_S, abs=0.005)


def test_a_slow_publisher_drops_stale_frames_instead_of_queueing(monkeypatch):
    """Publishing made slower (100 ms a frame) than capture (60 fps): stale frames are
    dropped, so every published frame is fresh, where a queue would age frame n by n x 83 ms
    (2.5 s by the 30th, and growing)."""
    from dronewrapper_camera_victure import node as camera_node

    real = camera_node.bgr_to_image

    def slow(*args):
        time.sleep(0.1)
        return real(*args)

    monkeypatch.setattr(camera_node, "bgr_to_image", slow)
    latencies: list[float] = []
    overrides = ["source=pattern", "fps=60", "width=320", "height=240"]
    with Running(overrides) as cam:
        cam.tester.subscribe(
            registry.IMAGE_RAW,
            lambda m: latencies.append(time.time() - m.header.stamp),
            camera="cam_frontal",
        )
        status = cam.wait_status(
            lambda s: s.frames_published >= 30 and s.frames_dropped >= 30, 30, "drops"
        )
    # the newest-frame slot keeps each frame's age to about one publishing time (0.1 s) plus
    # the machine's load
    assert max(latencies[5:]) < 1.0, latencies
    # every captured frame is published or counted as dropped, bar those captured during the
    # frame being published (100 ms at 60 fps: about 6) when the status was made
    in_flight = status.frames_captured - status.frames_published - status.frames_dropped
    assert 0 <= in_flight <= 12


class VanishingCaptures:
    """A fake V4L2 camera unplugged after ``frames`` reads of its first capture, until
    ``present`` is set again (a new capture each time it is opened)."""

    def __init__(self, frames: int) -> None:
        self.frames = frames
        self.present = True
        self.captures: list[FakeCapture] = []

    def factory(self, *args) -> FakeCapture:
        cap = FakeCapture()
        if self.captures:  # plugged in again: this one keeps working
            self.captures.append(cap)
            return cap
        limit = self.frames
        real_read = cap.read

        def read():
            if cap.reads >= limit:
                self.present = False  # unplugged: this capture fails from now on
                cap.reads += 1
                return False, None
            return real_read()

        cap.read = read
        self.captures.append(cap)
        return cap

    def check_present(self, path: str) -> None:
        from dronewrapper_camera_victure.sources import SourceError

        if not self.present:
            raise SourceError(f"no camera device {path} (devices found: none)")


def test_a_vanished_device_is_retried_with_backoff_and_reported(monkeypatch):
    from dronewrapper_camera_victure import sources

    device = VanishingCaptures(frames=20)
    monkeypatch.setattr(sources, "check_device_present", device.check_present)
    overrides = ["source=/dev/video0", "read_timeout=5", "max_read_failures=3",
                 "retry_initial=0.1", "retry_max=0.4"]  # fmt: skip
    with Running(overrides, device.factory) as cam:
        status = cam.wait_status(
            lambda s: s.state == "reconnecting" and s.open_failures >= 2, 20, "the loss reported"
        )
        assert "no camera device /dev/video0" in status.last_error
        seen = len(cam.raw)
        device.present = True  # plugged in again
        status = cam.wait_status(
            lambda s: s.reconnects >= 1 and s.state == "streaming", 20, "the reconnection"
        )
        wait_for(lambda: len(cam.raw) > seen + 5, 20, what="frames after the reconnection")
    assert len(device.captures) >= 2 and device.captures[0].released
    assert cam.result == [0]
