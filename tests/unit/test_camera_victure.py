"""camera_victure's pure parts: source kinds, config checks, V4L2 mode handling on a fake
capture, driver stamps, geometry, intrinsics through the geometry, the test pattern, the
newest-frame slot and the reconnection backoff."""

from __future__ import annotations

import threading

import cv2
import msgspec
import numpy as np
import pytest
from camera_fake import FakeCapture

from dronewrapper.runtime.clock import VirtualClock
from dronewrapper.runtime.config import ConfigError, load_config
from dronewrapper_camera_victure import sources
from dronewrapper_camera_victure.calibration import (
    CalibrationError,
    Intrinsics,
    load_calibration,
    transformed,
)
from dronewrapper_camera_victure.config import Config
from dronewrapper_camera_victure.listing import describe_devices
from dronewrapper_camera_victure.pattern import read_counter, render_pattern
from dronewrapper_camera_victure.reader import Backoff, Captured, FrameSlot, to_bgr
from dronewrapper_camera_victure.sources import Mode
from dronewrapper_camera_victure.transform import Transform


@pytest.mark.parametrize(
    ("source", "kind"),
    [
        ("0", "device"),
        ("/dev/video2", "device"),
        ("pattern", "pattern"),
        ("assets/video/vtest.avi", "file"),
        ("file:///tmp/a.mp4", "file"),
        ("rtsp://10.0.0.2:8554/cam", "url"),
        ("http://127.0.0.1:8080/stream.mjpg", "url"),
        ("udp://127.0.0.1:5000", "url"),
        ("rtp://127.0.0.1:5004", "url"),
    ],
)
def test_source_kinds(source, kind):
    assert sources.classify_source(source) == kind


def test_an_unknown_url_scheme_is_named():
    with pytest.raises(ValueError, match="unsupported URL scheme 'htp'"):
        sources.classify_source("htp://camera")


@pytest.mark.parametrize(
    ("override", "named"),
    [
        ("camera=cam_rear", "camera"),
        ("rotate=45", "rotate"),
        ("flip=diagonal", "flip"),
        ("pixel_format=H264", "pixel_format"),
        ("jpeg_quality=0", "jpeg_quality"),
        ("fps=.nan", "fps"),
        ("crop=[0,0,0,10]", "crop"),
        ("resize=[320]", "resize"),
        ("width=640", "width, height"),  # with height=0
        ("source=ftp://x/y", "URL scheme"),
        ("retry_max=0.1", "retry_max"),
        ("colour=red", "colour"),
    ],
)
def test_bad_config_names_the_key(override, named):
    extra = ["height=0"] if override.startswith("width") else []
    with pytest.raises(ConfigError, match=named):
        load_config(Config, None, [override, *extra])


def test_publishing_nothing_is_refused():
    with pytest.raises(ConfigError, match="nothing to publish"):
        load_config(Config, None, ["publish_raw=false"])


def test_pixel_format_is_case_insensitive():
    assert load_config(Config, None, ["pixel_format=mjpg"]).pixel_format == "MJPG"


def test_fourcc_round_trip():
    assert sources.fourcc_text(sources.fourcc_code("MJPG")) == "MJPG"
    assert sources.fourcc_code("MJPG") == cv2.VideoWriter_fourcc(*"MJPG")
    assert sources.fourcc_text(0) == ""


def test_request_mode_sets_format_before_size_and_reads_back():
    cap = FakeCapture()
    granted = sources.request_mode(cap, 1280, 720, 30, "MJPG")
    assert granted == Mode(1280, 720, 30.0, "MJPG")
    props = [prop for prop, _ in cap.sets]
    assert props.index(sources.CAP_PROP_FOURCC) < props.index(sources.CAP_PROP_FRAME_WIDTH)


def test_granted_values_differ_from_requested():
    cap = FakeCapture()
    granted = sources.request_mode(cap, 1280, 720, 30, "YUYV")  # YUYV 720p is 10 fps
    assert granted == Mode(1280, 720, 10.0, "YUYV")
    assert sources.mode_mismatches(Mode(1280, 720, 30, "YUYV"), granted) == []  # rate: reported
    granted = sources.request_mode(FakeCapture(), 1024, 768, 30, "MJPG")
    problems = sources.mode_mismatches(Mode(1024, 768, 30, "MJPG"), granted)
    assert problems == ["size 1024x768 (got 1280x720)"]


def test_a_format_the_device_lacks_is_a_mismatch():
    cap = FakeCapture(modes={"YUYV": [(640, 480, 30.0)]})
    granted = sources.request_mode(cap, 640, 480, 30, "MJPG")
    assert sources.mode_mismatches(Mode(640, 480, 30, "MJPG"), granted) == [
        "pixel format MJPG (got YUYV)"
    ]


def test_zero_size_leaves_the_default():
    cap = FakeCapture()
    assert sources.request_mode(cap, 0, 0, 0, "") == Mode(640, 480, 30.0, "YUYV")
    assert cap.sets == []


def test_probe_modes_lists_each_granted_mode_once():
    modes = sources.probe_modes(FakeCapture())
    assert [str(m) for m in modes] == [
        "640x480 MJPG @30 fps",
        "1280x720 MJPG @30 fps",
        "1920x1080 MJPG @30 fps",
        "640x480 YUYV @30 fps",
        "1280x720 YUYV @10 fps",
    ]


def test_describe_devices_on_fake_captures():
    caps = {"/dev/video0": FakeCapture(), "/dev/video1": FakeCapture(opened=False)}
    lines = describe_devices(list(caps), factory=lambda path, api, params: caps[path])
    assert lines[0] == "/dev/video0: default 640x480 YUYV @30 fps"
    assert "  1920x1080 MJPG @30 fps" in lines
    assert lines[-1].startswith("/dev/video1: cannot open")
    assert all(cap.released for cap in caps.values())


def test_driver_stamp_converts_monotonic_to_wall_clock():
    assert sources.driver_stamp(99_990.0, wall_now=1e9, mono_now=100.0) == pytest.approx(1e9 - 0.01)
    assert sources.driver_stamp(0.0, 1e9, 100.0) is None  # no driver stamp
    assert sources.driver_stamp(101_000.0, 1e9, 100.0) is None  # in the future
    assert sources.driver_stamp(5_000.0, 1e9, 100.0) is None  # a media position, not a time


def test_to_bgr_converts_grey_and_bgra_and_refuses_the_rest():
    assert to_bgr(np.zeros((4, 5), np.uint8)).shape == (4, 5, 3)
    assert to_bgr(np.zeros((4, 5, 4), np.uint8)).shape == (4, 5, 3)
    assert to_bgr(np.zeros((4, 5, 3), np.float32)) is None
    assert to_bgr(np.zeros((0, 5, 3), np.uint8)) is None
    assert to_bgr(np.zeros((4, 5, 2), np.uint8)) is None


def test_sdk_encode_helpers_round_trip():
    """The SDK's publishing helpers the service uses: bgr8 Image and JPEG, through the codec."""
    from dronewrapper.errors import DroneError
    from dronewrapper.images import bgr_to_image, bgr_to_jpeg, compressed_to_bgr, image_to_bgr
    from dronewrapper.msgs import CompressedImage, Image, codec

    frame = render_pattern(320, 240, 77, 1.7e9)
    msg = codec.decode(Image, codec.encode(bgr_to_image(frame, 1.7e9, "cam_ventral", 77)))
    assert (msg.width, msg.height, msg.step, msg.encoding) == (320, 240, 960, "bgr8")
    assert (msg.header.stamp, msg.header.frame_id, msg.header.seq) == (1.7e9, "cam_ventral", 77)
    np.testing.assert_array_equal(image_to_bgr(msg), frame)
    jpeg = codec.decode(CompressedImage, codec.encode(bgr_to_jpeg(frame, 2.0, "c", 3, 90)))
    assert jpeg.format == "jpeg" and jpeg.header.seq == 3
    assert read_counter(compressed_to_bgr(jpeg)) == 77
    with pytest.raises(DroneError, match="uint8 BGR"):
        bgr_to_image(np.zeros((4, 4), np.uint8), 0.0, "c")


# ---- geometry ----

TRANSFORMS = [
    Transform(flip="horizontal"),
    Transform(flip="vertical"),
    Transform(rotate=90),
    Transform(rotate=180),
    Transform(rotate=270),
    Transform(flip="horizontal", rotate=90, crop=(10, 100, 250, 250)),
    Transform(rotate=180, crop=(40, 30, 320, 240), resize=(640, 480)),
    Transform(resize=(320, 240)),
]


@pytest.mark.parametrize("transform", TRANSFORMS, ids=str)
def test_pixel_maps_follow_the_pixels(transform):
    """A marked pixel lands where the composed pixel map says."""
    width, height = 400, 300
    frame = np.zeros((height, width, 3), np.uint8)
    u, v = 123, 87
    frame[v - 2 : v + 3, u - 2 : u + 3] = 255
    out = transform.apply(frame)
    assert (out.shape[1], out.shape[0]) == transform.output_size(width, height)
    m = np.eye(3)
    for step in transform.steps(width, height):
        m = step.pixels @ m
    expect = m @ np.array([u, v, 1.0])
    ys, xs = np.nonzero(out[:, :, 0] > 100)
    assert xs.mean() == pytest.approx(expect[0], abs=0.6)
    assert ys.mean() == pytest.approx(expect[1], abs=0.6)


def test_identity_returns_the_frame_itself():
    frame = np.zeros((4, 4, 3), np.uint8)
    assert Transform().apply(frame) is frame


def test_a_crop_outside_the_frame_is_named():
    with pytest.raises(ValueError, match=r"crop \[0, 0, 500, 10\] does not fit the 480x640"):
        Transform(rotate=90, crop=(0, 0, 500, 10)).apply(np.zeros((480, 640, 3), np.uint8))


CAL = Intrinsics(
    width=640,
    height=480,
    distortion_model="plumb_bob",
    d=(-0.28, 0.09, 0.0012, -0.0007, -0.01),
    k=(520.0, 0.0, 318.0, 0.0, 515.0, 242.0, 0.0, 0.0, 1.0),
    r=(1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0),
    p=(520.0, 0.0, 318.0, 0.0, 0.0, 515.0, 242.0, 0.0, 0.0, 0.0, 1.0, 0.0),
)


def _project(cal: Intrinsics, points: np.ndarray) -> np.ndarray:
    k = np.array(cal.k).reshape(3, 3)
    image, _ = cv2.projectPoints(points, np.zeros(3), np.zeros(3), k, np.array(cal.d))
    return image.reshape(-1, 2)


@pytest.mark.parametrize("transform", TRANSFORMS, ids=str)
def test_intrinsics_follow_the_pixels(transform):
    """Projecting 3D points with the carried-over intrinsics (distortion included) gives the
    pixels the frame transform moves the original projections to."""
    rng = np.random.default_rng(3)
    points = np.column_stack([rng.uniform(-1.5, 1.5, 50), rng.uniform(-1, 1, 50), np.full(50, 3.0)])
    before = _project(CAL, points)
    m = np.eye(3)
    axes = np.eye(3)
    for step in transform.steps(CAL.width, CAL.height):
        m = step.pixels @ m
        a = np.eye(3)
        a[:2, :2] = step.axes
        axes = a @ axes
    moved = (m @ np.column_stack([before, np.ones(len(before))]).T).T[:, :2]
    after = _project(transformed(CAL, transform), points @ axes.T)
    np.testing.assert_allclose(after, moved, atol=1e-6)
    out = transformed(CAL, transform)
    assert (out.width, out.height) == transform.output_size(640, 480)
    p = np.array(out.p).reshape(3, 4)
    np.testing.assert_allclose(p[:, :3], np.array(out.k).reshape(3, 3), atol=1e-9)


def test_calibration_file_round_trip(tmp_path):
    file = tmp_path / "cam.yaml"
    file.write_text(
        "image_width: 640\nimage_height: 480\ncamera_name: victure\n"
        "camera_matrix: {rows: 3, cols: 3, data: [520, 0, 318, 0, 515, 242, 0, 0, 1]}\n"
        "distortion_model: plumb_bob\n"
        "distortion_coefficients: {rows: 1, cols: 5, data: [-0.28, 0.09, 0.0012, -0.0007, -0.01]}\n"
        "rectification_matrix: {rows: 3, cols: 3, data: [1, 0, 0, 0, 1, 0, 0, 0, 1]}\n"
    )
    cal = load_calibration(file)
    assert cal.k == CAL.k and cal.d == CAL.d
    assert cal.p == CAL.p  # a monocular camera's P defaults to [K | 0]


@pytest.mark.parametrize(
    ("text", "named"),
    [
        ("image_width: 640\n", "image_height"),
        ("image_width: 640\nimage_height: 480\ncamera_matrix: {data: [1, 2]}\n", "camera_matrix"),
        (
            "image_width: 640\nimage_height: 480\ndistortion_model: fancy\n"
            "camera_matrix: {data: [1, 0, 0, 0, 1, 0, 0, 0, 1]}\n",
            "distortion_model",
        ),
        ("[1, 2]\n", "mapping"),
    ],
)
def test_bad_calibration_names_the_field(tmp_path, text, named):
    file = tmp_path / "bad.yaml"
    file.write_text(text)
    with pytest.raises(CalibrationError, match=named):
        load_calibration(file)


def test_missing_calibration_file_is_named(tmp_path):
    with pytest.raises(CalibrationError, match=r"nope\.yaml"):
        load_calibration(tmp_path / "nope.yaml")


def test_the_shipped_config_and_calibration_load():
    from support import REPO

    config = load_config(
        Config, REPO / "services/camera_victure/dronewrapper_camera_victure/config/victure.yaml", []
    )
    assert (config.source_kind, config.rotate, config.pixel_format) == ("device", 180, "MJPG")
    cal = load_calibration(REPO / config.calibration_file)
    assert (cal.width, cal.height) == (config.width, config.height)


# ---- pattern, slot, backoff ----


@pytest.mark.parametrize("counter", [0, 1, 255, 123_456, 2**31 + 7])
def test_pattern_counter_survives_jpeg(counter):
    frame = render_pattern(640, 480, counter, 1.7e9)
    assert read_counter(frame) == counter
    jpeg = cv2.imdecode(cv2.imencode(".jpg", frame, [cv2.IMWRITE_JPEG_QUALITY, 50])[1], 1)
    assert read_counter(jpeg) == counter


def test_pattern_size_is_checked():
    with pytest.raises(ValueError, match="too small"):
        render_pattern(32, 32, 0, 0.0)


def _captured(n: int) -> Captured:
    return Captured(np.zeros((1, 1, 3), np.uint8), float(n), n)


def test_slot_keeps_only_the_newest():
    slot = FrameSlot()
    for n in range(5):
        slot.update(_captured(n))
    number, item = slot.take(0.0, 0)
    assert (number, item.number) == (5, 4)
    assert slot.take(0.01, number) is None


def _second_put_waiting():
    """A lossless slot holding frame 0 (not taken) and a thread putting frame 1 into it."""
    clock = VirtualClock()
    slot, stop = FrameSlot(clock=clock), threading.Event()
    slot.update(_captured(0), wait_taken=stop)
    second = clock.thread(lambda: slot.update(_captured(1), wait_taken=stop), "second")
    second.start()
    return clock, slot, stop, second


def test_lossless_slot_waits_until_taken():
    clock, slot, _, second = _second_put_waiting()
    clock.run_for(5.0)
    assert not second.finished  # blocked: frame 0 not taken yet, 5 s (virtual) on
    assert slot.take(0.0, 0)[1].number == 0
    clock.run_until(lambda: second.finished, 1.0, "frame 1 handed over once 0 was taken")
    assert slot.take(0.0, 1)[1].number == 1


def test_lossless_slot_gives_up_waiting_on_stop():
    clock, slot, stop, second = _second_put_waiting()
    clock.run_for(1.0)
    stop.set()
    clock.run_until(lambda: second.finished, 1.0, "the put to give up")
    assert slot.take(0.0, 0)[0] == 2  # frame 0 replaced, not taken


def test_backoff_doubles_to_the_maximum_and_resets():
    backoff = Backoff(0.25, 1.0)
    assert [backoff.next() for _ in range(5)] == [0.25, 0.5, 1.0, 1.0, 1.0]
    backoff.reset()
    assert backoff.next() == 0.25


def test_config_is_a_strict_struct():
    assert msgspec.structs.fields(Config)  # a msgspec Struct
    with pytest.raises(ConfigError, match="unknown field"):
        load_config(Config, None, ["nope=1"])
