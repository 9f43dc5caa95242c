"""Camera messages as BGR numpy arrays (OpenCV channel order), the newest frame only.

Both ways: messages to arrays (subscribers) and arrays to messages (camera publishers such as
camera_victure). Raw images (``sensor_msgs/Image``) are converted with numpy alone. JPEG/PNG
compressed images (for Wi-Fi links) are encoded and decoded with OpenCV, imported only when
needed, so the SDK itself depends on numpy alone.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from dronewrapper.errors import DroneError
from dronewrapper.msgs.sensor import CompressedImage, Image
from dronewrapper.msgs.std import Header

_CHANNELS = {"bgr8": 3, "rgb8": 3, "bgra8": 4, "rgba8": 4, "mono8": 1, "8UC3": 3, "8UC1": 1}


def image_to_bgr(msg: Image) -> np.ndarray:
    """A writable ``uint8`` array of shape (height, width, 3) in BGR order (mono8: (h, w)).

    Handles row padding (``step`` > width * channels) and converts rgb8/rgba8/bgra8 to BGR.

    Raises:
        DroneError: unknown encoding, or ``data`` shorter than ``height * step``.
    """
    channels = _CHANNELS.get(msg.encoding)
    if channels is None:
        raise DroneError(f"unsupported image encoding {msg.encoding!r} (expected bgr8)")
    row = msg.width * channels
    step = msg.step or row
    if msg.height <= 0 or msg.width <= 0 or step < row or len(msg.data) < msg.height * step:
        raise DroneError(
            f"malformed image: {msg.width}x{msg.height} {msg.encoding} step {msg.step}, "
            f"{len(msg.data)} bytes"
        )
    flat = np.frombuffer(msg.data, dtype=np.uint8, count=msg.height * step)
    pixels = flat.reshape(msg.height, step)[:, :row]
    if channels == 1:
        return pixels.reshape(msg.height, msg.width).copy()
    pixels = pixels.reshape(msg.height, msg.width, channels)
    if msg.encoding in ("rgb8", "rgba8"):
        return np.array(pixels[:, :, 2::-1], order="C")
    return np.array(pixels[:, :, :3], order="C")


def jpeg_decoder() -> Any:
    """The ``cv2`` module, imported on first use.

    Raises:
        DroneError: OpenCV is not installed (the message says what to install).
    """
    try:
        import cv2
    except ImportError as exc:
        raise DroneError(
            "compressed images need OpenCV to decode JPEG: pip install 'dronewrapper[images]' "
            "(from the repository: pip install './sdk[images]'), or use "
            "DroneWrapper(compressed_images=False) for raw images"
        ) from exc
    return cv2


def has_jpeg_decoder() -> bool:
    """True if OpenCV can be imported (JPEG frames can be decoded)."""
    try:
        jpeg_decoder()
    except DroneError:
        return False
    return True


def compressed_to_bgr(msg: CompressedImage) -> np.ndarray:
    """Decode a JPEG/PNG CompressedImage to a BGR ``uint8`` array (needs OpenCV).

    Raises:
        DroneError: OpenCV is not installed, or the bytes do not decode.
    """
    cv2 = jpeg_decoder()
    image = cv2.imdecode(np.frombuffer(msg.data, dtype=np.uint8), cv2.IMREAD_COLOR)
    if image is None:
        raise DroneError(f"cannot decode a {len(msg.data)}-byte {msg.format!r} image")
    return image


def bgr_to_image(bgr: np.ndarray, stamp: float, frame_id: str, seq: int = 0) -> Image:
    """A ``bgr8`` Image of a (height, width, 3) ``uint8`` array (``step`` = width * 3).

    ``stamp`` is the capture time (epoch s), ``frame_id`` the camera name, ``seq`` the frame
    number. ``data`` is a view of the array (no copy): publish the message before changing the
    array.

    Raises:
        DroneError: the array is not (h, w, 3) uint8.
    """
    if bgr.dtype != np.uint8 or bgr.ndim != 3 or bgr.shape[2] != 3:
        raise DroneError(f"expected a (h, w, 3) uint8 BGR array, got {bgr.shape} {bgr.dtype}")
    height, width = bgr.shape[:2]
    return Image(
        header=Header(stamp=stamp, frame_id=frame_id, seq=seq),
        height=height,
        width=width,
        encoding="bgr8",
        step=width * 3,
        data=memoryview(np.ascontiguousarray(bgr).reshape(-1)),
    )


def bgr_to_jpeg(
    bgr: np.ndarray, stamp: float, frame_id: str, seq: int = 0, quality: int = 80
) -> CompressedImage:
    """A JPEG CompressedImage of a BGR array at ``quality`` 1..100 (needs OpenCV); the header
    as :func:`bgr_to_image`'s.

    Raises:
        DroneError: OpenCV is not installed, or the encoder refused the array.
    """
    cv2 = jpeg_decoder()
    ok, buffer = cv2.imencode(".jpg", bgr, [cv2.IMWRITE_JPEG_QUALITY, int(quality)])
    if not ok:
        raise DroneError(f"cannot JPEG-encode a {bgr.shape} {bgr.dtype} array")
    header = Header(stamp=stamp, frame_id=frame_id, seq=seq)
    return CompressedImage(header=header, format="jpeg", data=buffer.tobytes())
