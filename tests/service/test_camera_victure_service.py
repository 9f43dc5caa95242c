"""The camera_victure service in this process, on the fake bus and in virtual time: a real video
file, the test pattern, truncated and damaged files, calibration, and start-up errors (a fake
V4L2 capture stands in for a device). Time (pacing, stale frames, timeouts, backoff, status
period, stamps) is its node's clock (virtual), so what it does in time is judged exactly,
however loaded the machine. The same service on a real Zenoh router (the wiring):
tests/integration/test_camera_victure_router.py."""

from __future__ import annotations

import random
import re

import numpy as np
import pytest
from camera_fake import EXPOSURE_AGE_S, FakeCapture
from camera_running import CALIBRATION, VIDEO, Running

from dronewrapper.images import compressed_to_bgr, image_to_bgr
from dronewrapper.msgs import registry
from dronewrapper.runtime.clock import VirtualClock
from dronewrapper_camera_victure.calibration import load_calibration, transformed
from dronewrapper_camera_victure.node import transform_of
from dronewrapper_camera_victure.pattern import read_counter

EXACT = 1e-6
"""Tolerance of a stamp (s): virtual time is exact, bar float rounding at epoch magnitudes."""

SMALL = "crop=[288,216,192,144]"
"""The middle of vtest.avi's 768x576 frames: small messages, and a view (a resize would cost
more than decoding the frame)."""


def test_a_file_played_once_as_fast_as_possible_loses_no_frame():
    overrides = [f"source={VIDEO}", "loop=false", "realtime=false", SMALL]
    with Running(overrides) as cam:
        cam.until(lambda: cam.result, 60, "the end of the file")
        status = cam.wait_status(lambda s: s.state == "ended", 5, "the final status")
    assert cam.result == [0]
    # every frame published, in order
    assert [m.header.seq for m in cam.raw] == list(range(795))
    assert (cam.raw[0].width, cam.raw[0].height) == (192, 144)
    assert status.frames_captured == status.frames_published == 795
    assert status.frames_dropped == 0 and status.truncated == 0


def test_a_file_played_at_its_own_rate_is_stamped_at_it():
    """vtest.avi is 10 fps: realtime play reads a frame every 0.1 s, each stamped when read,
    raw and JPEG alike."""
    with Running([f"source={VIDEO}", "jpeg=true"]) as cam:
        raw = cam.until(lambda: len(cam.raw) >= 12 and list(cam.raw), 5, "12 frames")
        jpeg = cam.jpeg.value
    img = raw[-1]
    assert (img.width, img.height, img.encoding) == (768, 576, "bgr8")
    assert image_to_bgr(img).std() > 5  # a real picture, not a blank buffer
    assert jpeg.data[:2] == b"\xff\xd8"
    assert [m.header.seq for m in raw] == list(range(len(raw)))
    stamps = np.array([m.header.stamp for m in raw])
    assert np.diff(stamps) == pytest.approx(np.full(len(stamps) - 1, 0.1), abs=EXACT)
    assert jpeg.header.stamp == pytest.approx(stamps[jpeg.header.seq], abs=EXACT)


def test_pattern_counter_flip_rotate_pacing_and_status():
    overrides = ["source=pattern", "fps=30", "rotate=180", "width=320", "height=240", "jpeg=true"]
    with Running(overrides) as cam:
        statuses: list = []
        cam.tester.subscribe(registry.CAMERA_STATUS, statuses.append, camera="cam_frontal")
        raw = cam.until(lambda: len(statuses) >= 3 and list(cam.raw), 5, "three statuses")
        statuses = statuses[:3]  # not the final one, at the stop
    frames = [image_to_bgr(m) for m in raw]
    counters = [read_counter(np.rot90(f, 2)) for f in frames]  # undo the rotation
    assert counters == [m.header.seq for m in raw] == list(range(len(frames)))
    assert read_counter(frames[-1]) != counters[-1] or counters[-1] == 0  # it was rotated
    assert read_counter(np.rot90(compressed_to_bgr(cam.jpeg.value), 2)) == (
        cam.jpeg.value.header.seq
    )
    # paced at 30 fps, never in bursts: capture stamps exactly 1/30 s apart
    stamps = np.array([m.header.stamp for m in raw])
    assert np.diff(stamps) == pytest.approx(np.full(len(stamps) - 1, 1 / 30), abs=EXACT)
    # a status every second (checked after each frame: at most a frame period late)
    periods = np.diff([s.header.stamp for s in statuses])
    assert all(1.0 - EXACT <= p <= 1.0 + 1 / 30 + EXACT for p in periods), periods
    status = statuses[-1]
    assert status.state == "streaming" and status.source == "pattern"
    assert (status.width, status.height) == (320, 240)
    assert status.fps_measured == pytest.approx(30, abs=1)  # 30 or 31 frames in about 1 s
    assert status.frames_captured == status.frames_published and status.frames_dropped == 0
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
        cam.until(lambda: cam.info.count >= 3 and cam.raw, 20, "camera_info")
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
    """Played at its own rate (as fast as possible, a looping file takes no virtual time at
    all, so no status would ever be due)."""
    path = _damaged(tmp_path, "truncated.avi", lambda d: d[: len(d) // 20])  # 27 frames
    with Running([f"source={path}", SMALL]) as cam:
        status = cam.wait_status(lambda s: s.truncated >= 2, 30, "two truncated passes")
        assert cam.thread.is_alive()
        raw = list(cam.raw)
    match = re.search(r"ended at frame (\d+) of 795 \(truncated", status.last_error)
    assert match, status.last_error
    per_pass = int(match[1])
    assert per_pass >= 20 and len(raw) >= 2 * per_pass
    assert status.frames_published == len(raw) and status.frames_dropped == 0
    # looped: the frame after the last decodable one is the file's first again
    assert np.array_equal(image_to_bgr(raw[per_pass]), image_to_bgr(raw[0]))
    assert not np.array_equal(image_to_bgr(raw[per_pass - 1]), image_to_bgr(raw[0]))


def test_a_corrupt_file_is_survived(tmp_path):
    def corrupt(data: bytearray) -> bytes:
        rng = random.Random(1)
        for _ in range(200):
            at = rng.randrange(20_000, len(data) - 100)
            data[at : at + 50] = rng.randbytes(50)
        return bytes(data)

    path = _damaged(tmp_path, "corrupt.avi", corrupt)
    overrides = [f"source={path}", "realtime=false", "loop=false", SMALL]
    with Running(overrides) as cam:
        cam.until(lambda: cam.result, 60, "the end of the damaged file")
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
        cam.until(lambda: cam.result, 15, "exit")
    assert cam.result == [2]
    assert message in caplog.text


def _device_node(overrides, cap, monkeypatch):
    """The service on a fake V4L2 capture posing as /dev/video0, in the capture's time."""
    from dronewrapper_camera_victure import sources

    monkeypatch.setattr(sources, "check_device_present", lambda path: None)
    return Running(["source=/dev/video0", *overrides], lambda *a: cap, clock=cap.clock)


def test_device_unsupported_mode_exits_2(caplog, monkeypatch):
    cap = FakeCapture(clock=VirtualClock())
    with _device_node(["width=1024", "height=768", "pixel_format=MJPG"], cap, monkeypatch) as c:
        c.until(lambda: c.result, 15, "exit")
    assert c.result == [2]
    assert "camera /dev/video0 does not support size 1024x768 (got 1280x720)" in caplog.text
    assert cap.released


def test_device_busy_exits_2_after_the_open_timeout(caplog, monkeypatch):
    cap = FakeCapture(busy=True, clock=VirtualClock())
    started = cap.clock.monotonic()
    with _device_node(["open_timeout=0.5"], cap, monkeypatch) as c:
        c.until(lambda: c.result, 15, "exit")
        waited = c.clock.monotonic() - started
    assert c.result == [2]
    assert "camera /dev/video0 gives no frames within 0.5 s (busy" in caplog.text
    assert 0.5 - EXACT <= waited <= 0.55 + EXACT  # tried every 0.05 s for open_timeout
    assert cap.released


def test_device_mode_granted_and_driver_stamps(monkeypatch):
    cap = FakeCapture(clock=VirtualClock())
    overrides = ["width=1280", "height=720", "pixel_format=YUYV", "fps=30"]
    with _device_node(overrides, cap, monkeypatch) as c:
        status = c.wait_status(lambda s: s.frames_published >= 3, 20, "device frames")
        raw = list(c.raw)
    assert (status.width, status.height, status.pixel_format) == (1280, 720, "YUYV")
    assert status.fps == 10.0  # what the device granted, reported
    assert status.fps_measured == pytest.approx(10, abs=1)  # and what it gives
    assert (raw[-1].width, raw[-1].height) == (1280, 720)
    # each stamp is its driver's timestamp (50 ms before the read), not the read time
    for img in raw:
        read_number = int(image_to_bgr(img)[0, 0, 0])  # the fake fills frame n with n % 256
        read_wall = cap.read_walls[read_number]
        assert img.header.stamp == pytest.approx(read_wall - EXPOSURE_AGE_S, abs=EXACT)
    stamps = np.array([m.header.stamp for m in raw])
    assert np.diff(stamps) == pytest.approx(np.full(len(stamps) - 1, 0.1), abs=EXACT)


def test_a_slow_publisher_drops_stale_frames_instead_of_queueing(monkeypatch):
    """Publishing made slower (100 ms a frame) than capture (60 fps): stale frames are
    dropped, so every published frame is fresh, where a queue would age frame n by n x 83 ms
    (2.5 s by the 30th, and growing)."""
    from dronewrapper_camera_victure import node as camera_node

    clock = VirtualClock()
    real = camera_node.bgr_to_image

    def slow(*args):
        clock.sleep(0.1)
        return real(*args)

    monkeypatch.setattr(camera_node, "bgr_to_image", slow)
    ages: list[float] = []
    overrides = ["source=pattern", "fps=60", "width=320", "height=240"]
    with Running(overrides, clock=clock) as cam:
        cam.tester.subscribe(
            registry.IMAGE_RAW,
            lambda m: ages.append(clock.time() - m.header.stamp),
            camera="cam_frontal",
        )
        status = cam.wait_status(
            lambda s: s.frames_published >= 30 and s.frames_dropped >= 30, 10, "drops"
        )
        ages = list(ages)
        seqs = [m.header.seq for m in cam.raw]
    # the newest frame is taken: its age when published is the 0.1 s spent publishing it plus
    # at most one capture period (1/60 s) it waited in the slot
    assert all(0.1 - EXACT <= age <= 0.1 + 1 / 60 + EXACT for age in ages), ages
    # 0.1 s of publishing is 6 captures at 60 fps: each published frame is the 6th after the
    # previous one (5 dropped between), from the first frame on
    assert np.diff(seqs).tolist() == [6] * (len(seqs) - 1), seqs
    # every captured frame is published or counted as dropped, bar those captured since the
    # last one was taken (during its publishing: 6, one of them perhaps at the same instant)
    in_flight = status.frames_captured - status.frames_published - status.frames_dropped
    assert 5 <= in_flight <= 6


class VanishingCaptures:
    """A fake V4L2 camera unplugged after ``frames`` reads of its first capture, until
    ``present`` is set again (a new capture each time it is opened). ``checks``: the times
    (Unix s) its presence was checked, i.e. it was opened or tried."""

    def __init__(self, frames: int, clock: VirtualClock) -> None:
        self.frames = frames
        self.clock = clock
        self.present = True
        self.captures: list[FakeCapture] = []
        self.checks: list[float] = []

    def factory(self, *args) -> FakeCapture:
        cap = FakeCapture(clock=self.clock)
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

        self.checks.append(self.clock.time())
        if not self.present:
            raise SourceError(f"no camera device {path} (devices found: none)")


def test_a_vanished_device_is_retried_with_backoff_and_reported(monkeypatch):
    from dronewrapper_camera_victure import sources

    device = VanishingCaptures(frames=20, clock=VirtualClock())
    monkeypatch.setattr(sources, "check_device_present", device.check_present)
    overrides = ["source=/dev/video0", "read_timeout=5", "max_read_failures=3",
                 "retry_initial=0.1", "retry_max=0.4"]  # fmt: skip
    with Running(overrides, device.factory, clock=device.clock) as cam:
        status = cam.wait_status(
            lambda s: s.state == "reconnecting" and s.open_failures >= 4, 20, "the loss reported"
        )
        assert "no camera device /dev/video0" in status.last_error
        seen, lost_at = len(cam.raw), device.captures[0].read_walls[20]
        device.present = True  # plugged in again
        status = cam.wait_status(
            lambda s: s.reconnects >= 1 and s.state == "streaming", 20, "the reconnection"
        )
        raw = cam.until(lambda: len(cam.raw) > seen + 5 and list(cam.raw), 5, "frames again")
    assert seen == 20  # every frame before the loss published
    # lost at the 3rd failed read in a row (at once), then tried 0.1 s later, backing off
    # 0.2, 0.4, 0.4 ... s (retry_max) until it is back; the try that finds it opens it
    tries = np.array(device.checks[1:]) - lost_at
    gaps = np.diff(tries)
    assert tries[0] == pytest.approx(0.1, abs=EXACT)
    assert gaps == pytest.approx([0.2] + [0.4] * (len(gaps) - 1), abs=EXACT)
    assert status.open_failures == len(tries) - 1 and status.reconnects == 1
    # frames flow again from the reopened capture: the first one read 1/30 s after the try
    # that found it (a read at 30 fps), stamped by its driver
    assert [m.header.seq for m in raw] == list(range(len(raw)))
    first_read = device.captures[1].read_walls[1]
    assert first_read - device.checks[-1] == pytest.approx(1 / 30, abs=EXACT)
    assert raw[seen].header.stamp == pytest.approx(first_read - EXPOSURE_AGE_S, abs=EXACT)
    assert len(device.captures) == 2 and device.captures[0].released
    assert cam.result == [0]
