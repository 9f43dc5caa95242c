"""Image messages to BGR numpy arrays (raw with numpy; JPEG with OpenCV)."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from dronewrapper.errors import DroneError
from dronewrapper.images import compressed_to_bgr, image_to_bgr
from dronewrapper.msgs import CompressedImage, Image


def bgr_pattern(h: int = 4, w: int = 5) -> np.ndarray:
    img = np.zeros((h, w, 3), np.uint8)
    img[..., 0] = 200  # blue
    img[..., 1] = np.arange(w, dtype=np.uint8)[None, :]
    img[..., 2] = np.arange(h, dtype=np.uint8)[:, None] * 10
    return img


def test_bgr8_round_trip_and_writable():
    img = bgr_pattern()
    msg = Image(height=4, width=5, encoding="bgr8", step=15, data=img.tobytes())
    out = image_to_bgr(msg)
    assert out.shape == (4, 5, 3) and out.dtype == np.uint8
    assert np.array_equal(out, img)
    out[0, 0] = 0  # the caller may draw on it (the message bytes are read-only)


def test_rgb8_is_converted_to_bgr():
    img = bgr_pattern()
    rgb = img[:, :, ::-1].copy()
    msg = Image(height=4, width=5, encoding="rgb8", step=15, data=rgb.tobytes())
    assert np.array_equal(image_to_bgr(msg), img)


def test_row_padding_is_dropped():
    img = bgr_pattern()
    padded = np.zeros((4, 16), np.uint8)
    padded[:, :15] = img.reshape(4, 15)
    msg = Image(height=4, width=5, encoding="bgr8", step=16, data=padded.tobytes())
    assert np.array_equal(image_to_bgr(msg), img)


def test_mono8_gives_two_dimensions():
    msg = Image(height=2, width=3, encoding="mono8", step=3, data=bytes(range(6)))
    assert image_to_bgr(msg).tolist() == [[0, 1, 2], [3, 4, 5]]


@pytest.mark.parametrize(
    "msg",
    [
        Image(height=4, width=5, encoding="bgr8", step=15, data=b"\0" * 10),
        Image(height=4, width=5, encoding="yuv422", step=10, data=b"\0" * 40),
        Image(height=0, width=0, encoding="bgr8", data=b""),
    ],
)
def test_malformed_images_raise_a_clear_error(msg):
    with pytest.raises(DroneError, match="image"):
        image_to_bgr(msg)


def test_jpeg_decodes_to_bgr():
    img = np.zeros((24, 32, 3), np.uint8)
    img[:, :16] = (0, 0, 255)  # red on the left (BGR)
    ok, jpeg = cv2.imencode(".jpg", img, [cv2.IMWRITE_JPEG_QUALITY, 95])
    assert ok
    out = compressed_to_bgr(CompressedImage(format="jpeg", data=jpeg.tobytes()))
    assert out.shape == (24, 32, 3)
    assert out[12, 4, 2] > 200 and out[12, 4, 0] < 50  # still red, still BGR
    with pytest.raises(DroneError, match="decode"):
        compressed_to_bgr(CompressedImage(format="jpeg", data=b"not a jpeg"))
