"""Camera messages to BGR arrays, with every way a frame can be bad named (pure).

Raw ``Image`` encodings accepted: ``bgr8`` (the system's default), ``rgb8``, ``mono8``,
``bgra8``, ``rgba8``; rows may be padded (``step`` >= width x channels). ``CompressedImage``:
anything OpenCV decodes (JPEG, PNG).
"""

from __future__ import annotations

import cv2
import numpy as np

from dronewrapper.msgs import CompressedImage, Header, Image

CHANNELS = {"bgr8": 3, "rgb8": 3, "mono8": 1, "bgra8": 4, "rgba8": 4}
_TO_BGR = {
    "rgb8": cv2.COLOR_RGB2BGR,
    "mono8": cv2.COLOR_GRAY2BGR,
    "bgra8": cv2.COLOR_BGRA2BGR,
    "rgba8": cv2.COLOR_RGBA2BGR,
}


class BadFrame(ValueError):
    """A frame that cannot be used; ``reason`` is a short counter key."""

    def __init__(self, reason: str, message: str) -> None:
        super().__init__(message)
        self.reason = reason


def image_to_bgr(msg: Image) -> np.ndarray:
    """The frame as an HxWx3 uint8 BGR array (a copy only when conversion needs one).

    Raises:
        BadFrame: empty data, unknown encoding, or data size not matching the geometry.
    """
    if not msg.data:
        raise BadFrame("empty", "image with empty data")
    if msg.width <= 0 or msg.height <= 0:
        raise BadFrame("bad_size", f"image size {msg.width}x{msg.height} is not positive")
    channels = CHANNELS.get(msg.encoding.lower())
    if channels is None:
        known = ", ".join(CHANNELS)
        raise BadFrame("encoding", f"unknown image encoding {msg.encoding!r} (known: {known})")
    row = msg.width * channels
    step = msg.step or row
    if step < row or len(msg.data) != step * msg.height:
        raise BadFrame(
            "bad_size",
            f"{msg.width}x{msg.height} {msg.encoding} needs {row * msg.height} bytes "
            f"(step {step}), got {len(msg.data)}",
        )
    array = np.frombuffer(msg.data, np.uint8).reshape(msg.height, step)[:, :row]
    array = array.reshape(msg.height, msg.width, channels)
    encoding = msg.encoding.lower()
    if encoding == "bgr8":
        return array if step == row else np.ascontiguousarray(array)
    if channels == 1:
        array = array[:, :, 0]
    return cv2.cvtColor(np.ascontiguousarray(array), _TO_BGR[encoding])


def compressed_to_bgr(msg: CompressedImage) -> np.ndarray:
    """Decode a JPEG/PNG frame to BGR.

    Raises:
        BadFrame: empty data or bytes OpenCV cannot decode.
    """
    if not msg.data:
        raise BadFrame("empty", "compressed image with empty data")
    image = cv2.imdecode(np.frombuffer(msg.data, np.uint8), cv2.IMREAD_COLOR)
    if image is None or image.size == 0:
        raise BadFrame("undecodable", f"cannot decode {len(msg.data)} bytes of {msg.format!r}")
    return image


def bgr_to_image(bgr: np.ndarray, stamp: float, frame_id: str, seq: int = 0) -> Image:
    """A bgr8 Image message of an array (used by tests, benchmarks and tools)."""
    height, width = bgr.shape[:2]
    return Image(
        header=Header(stamp=stamp, frame_id=frame_id, seq=seq),
        height=height,
        width=width,
        encoding="bgr8",
        step=width * 3,
        data=np.ascontiguousarray(bgr).tobytes(),
    )
