"""Camera messages to BGR: encodings, padded rows, and every bad frame named."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from dronewrapper.msgs import CompressedImage, Image
from dronewrapper_perception.frames import (
    BadFrame,
    bgr_to_image,
    compressed_to_bgr,
    image_to_bgr,
)


def pattern(h=6, w=8) -> np.ndarray:
    return np.arange(h * w * 3, dtype=np.uint8).reshape(h, w, 3)


def test_bgr8_roundtrip_and_stamp():
    img = pattern()
    msg = bgr_to_image(img, 12.5, "cam_frontal", 3)
    assert msg.header.stamp == 12.5 and msg.step == 24
    assert np.array_equal(image_to_bgr(msg), img)


def test_rgb_mono_and_alpha_become_bgr():
    img = pattern()
    rgb = Image(width=8, height=6, encoding="rgb8", data=img[:, :, ::-1].tobytes())
    assert np.array_equal(image_to_bgr(rgb), img)
    gray = np.arange(48, dtype=np.uint8).reshape(6, 8)
    mono = image_to_bgr(Image(width=8, height=6, encoding="mono8", data=gray.tobytes()))
    assert mono.shape == (6, 8, 3) and np.array_equal(mono[:, :, 1], gray)
    bgra = np.dstack((img, np.full((6, 8), 255, np.uint8)))
    assert np.array_equal(
        image_to_bgr(Image(width=8, height=6, encoding="bgra8", data=bgra.tobytes())), img
    )


def test_padded_rows():
    img = pattern()
    padded = np.zeros((6, 32), np.uint8)
    padded[:, :24] = img.reshape(6, 24)
    msg = Image(width=8, height=6, encoding="bgr8", step=32, data=padded.tobytes())
    assert np.array_equal(image_to_bgr(msg), img)


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
    with pytest.raises(BadFrame) as info:
        image_to_bgr(msg)
    assert info.value.reason == reason


def test_compressed_frames():
    img = np.zeros((48, 64, 3), np.uint8)
    img[:, :32] = (0, 0, 255)
    ok, jpeg = cv2.imencode(".jpg", img)
    assert ok
    out = compressed_to_bgr(CompressedImage(format="jpeg", data=jpeg.tobytes()))
    assert out.shape == (48, 64, 3) and out[10, 10, 2] > 200 and out[10, 50, 2] < 50
    with pytest.raises(BadFrame) as info:
        compressed_to_bgr(CompressedImage(format="jpeg", data=b"not a jpeg at all"))
    assert info.value.reason == "undecodable"
    with pytest.raises(BadFrame) as info:
        compressed_to_bgr(CompressedImage(format="jpeg", data=b""))
    assert info.value.reason == "empty"
