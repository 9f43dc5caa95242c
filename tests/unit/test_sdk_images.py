"""Image messages to BGR numpy arrays: the one decoder (SDK, perception, tools).

Every decoded frame is uint8 (height, width, 3) BGR, whatever the encoding (mono8 included);
every bad frame raises BadFrame with a reason a service can count.
"""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from dronewrapper.errors import DroneError
from dronewrapper.images import BadFrame, bgr_to_image, compressed_to_bgr, image_to_bgr
from dronewrapper.msgs import CompressedImage, Image


def bgr_pattern(h: int = 4, w: int = 5) -> np.ndarray:
    img = np.zeros((h, w, 3), np.uint8)
    img[..., 0] = 200  # blue
    img[..., 1] = np.arange(w, dtype=np.uint8)[None, :]
    img[..., 2] = np.arange(h, dtype=np.uint8)[:, None] * 10
    return img


def test_bgr8_round_trip_stamp_and_writable():
    img = bgr_pattern()
    msg = bgr_to_image(img, 12.5, "cam_frontal", 3)
    assert msg.header.stamp == 12.5 and msg.header.seq == 3 and msg.step == 15
    out = image_to_bgr(msg)
    assert out.shape == (4, 5, 3) and out.dtype == np.uint8
    assert np.array_equal(out, img)
    out[0, 0] = 0  # the caller may draw on it (the message bytes are read-only)


def test_bgr8_without_copy_is_a_view_of_the_bytes():
    img = bgr_pattern()
    data = img.tobytes()
    out = image_to_bgr(Image(height=4, width=5, encoding="bgr8", step=15, data=data), copy=False)
    assert np.array_equal(out, img) and not out.flags.writeable


@pytest.mark.parametrize("encoding", ["mono8", "MONO8", "8UC1"])
def test_mono_is_height_width_3_like_every_frame(encoding):
    """The shape is pinned: mono is replicated to (h, w, 3), never (h, w) or (h, w, 1)."""
    gray = np.arange(6, dtype=np.uint8).reshape(2, 3)
    out = image_to_bgr(Image(height=2, width=3, encoding=encoding, step=3, data=gray.tobytes()))
    assert out.shape == (2, 3, 3) and out.dtype == np.uint8
    for channel in range(3):
        assert np.array_equal(out[:, :, channel], gray)


@pytest.mark.parametrize("encoding", ["rgb8", "bgra8", "rgba8", "8UC3"])
def test_colour_encodings_become_bgr(encoding):
    img = bgr_pattern()
    alpha = np.full((4, 5, 1), 255, np.uint8)
    pixels = {
        "rgb8": img[:, :, ::-1],
        "bgra8": np.concatenate((img, alpha), axis=2),
        "rgba8": np.concatenate((img[:, :, ::-1], alpha), axis=2),
        "8UC3": img,
    }[encoding]
    msg = Image(height=4, width=5, encoding=encoding, data=np.ascontiguousarray(pixels).tobytes())
    out = image_to_bgr(msg)
    assert out.shape == (4, 5, 3) and np.array_equal(out, img)


@pytest.mark.parametrize("copy", [True, False])
def test_row_padding_is_dropped(copy):
    img = bgr_pattern()
    padded = np.zeros((4, 16), np.uint8)
    padded[:, :15] = img.reshape(4, 15)
    msg = Image(height=4, width=5, encoding="bgr8", step=16, data=padded.tobytes())
    assert np.array_equal(image_to_bgr(msg, copy=copy), img)


@pytest.mark.parametrize(
    ("msg", "reason"),
    [
        (Image(width=8, height=6, encoding="bgr8", data=b""), "empty"),
        (Image(width=8, height=6, encoding="bgr8", data=b"\0" * 100), "bad_size"),
        (Image(width=8, height=6, encoding="bgr8", data=b"\0" * (8 * 6 * 3 + 1)), "bad_size"),
        (Image(width=0, height=6, encoding="bgr8", data=b"\0" * 10), "bad_size"),
        (Image(width=8, height=6, encoding="yuv422", data=b"\0" * 96), "encoding"),
        (Image(width=8, height=6, encoding="bgr8", step=10, data=b"\0" * 60), "bad_size"),
    ],
)
def test_bad_raw_frames_named(msg, reason):
    with pytest.raises(BadFrame, match="image") as info:
        image_to_bgr(msg)
    assert info.value.reason == reason
    assert isinstance(info.value, DroneError)  # an SDK user catches DroneError


def test_compressed_frames():
    img = np.zeros((24, 32, 3), np.uint8)
    img[:, :16] = (0, 0, 255)  # red on the left (BGR)
    ok, jpeg = cv2.imencode(".jpg", img, [cv2.IMWRITE_JPEG_QUALITY, 95])
    assert ok
    out = compressed_to_bgr(CompressedImage(format="jpeg", data=jpeg.tobytes()))
    assert out.shape == (24, 32, 3)
    assert out[12, 4, 2] > 200 and out[12, 4, 0] < 50  # still red, still BGR
    with pytest.raises(BadFrame, match="decode") as info:
        compressed_to_bgr(CompressedImage(format="jpeg", data=b"not a jpeg"))
    assert info.value.reason == "undecodable"
    with pytest.raises(BadFrame) as info:
        compressed_to_bgr(CompressedImage(format="jpeg", data=b""))
    assert info.value.reason == "empty"
