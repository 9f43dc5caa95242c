"""Camera messages as BGR numpy arrays (OpenCV channel order): the one decoder of the project.

Both ways: messages to arrays (the SDK, perception, tools) and arrays to messages (camera
publishers such as camera_victure). Raw images (``sensor_msgs/Image``) are converted with numpy
alone. JPEG/PNG compressed images (for Wi-Fi links) are encoded and decoded with OpenCV, imported
only when needed, so the SDK itself depends on numpy alone.

Shapes: every decoded frame is ``uint8`` (height, width, 3) in BGR order, whatever the encoding;
``mono8`` is replicated into the three channels, alpha is dropped. A bad frame raises
:class:`BadFrame`, whose ``reason`` is a short key a service can count.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from dronewrapper.errors import DroneError
from dronewrapper.msgs.sensor import CompressedImage, Image
from dronewrapper.msgs.std import Header

CHANNELS = {"bgr8": 3, "rgb8": 3, "bgra8": 4, "rgba8": 4, "mono8": 1, "8uc3": 3, "8uc1": 1}
"""Raw encodings understood (lower case; matched case-insensitively) and their channel counts."""


class BadFrame(DroneError, ValueError):
    """A frame that cannot be used; ``reason`` is a short counter key.

    Reasons: ``empty`` (no bytes), ``bad_size`` (geometry and byte count disagree),
    ``encoding`` (unknown raw encoding), ``undecodable`` (compressed bytes OpenCV refuses).
    Services add their own (perception: ``bad_stamp``, ``processing_error``).
    """

    def __init__(self, reason: str, message: str) -> None:
        super().__init__(message)
        self.reason = reason


def image_to_bgr(msg: Image, *, copy: bool = True) -> np.ndarray:
    """A ``uint8`` array of shape (height, width, 3) in BGR order.

    Handles row padding (``step`` > width * channels), converts rgb8/rgba8/bgra8 to BGR and
    replicates mono8 into three channels. With ``copy=False`` an unpadded bgr8 frame comes back
    as a read-only view of the message bytes (no copy); otherwise the array is a writable copy.

    Raises:
        BadFrame: empty data, unknown encoding, or ``data`` not ``height * step`` bytes.
    """
    if not msg.data:
        raise BadFrame("empty", "image with empty data")
    if msg.width <= 0 or msg.height <= 0:
        raise BadFrame("bad_size", f"image size {msg.width}x{msg.height} is not positive")
    encoding = msg.encoding.lower()
    channels = CHANNELS.get(encoding)
    if channels is None:
        known = ", ".join(CHANNELS)
        raise BadFrame("encoding", f"unknown image encoding {msg.encoding!r} (known: {known})")
    row = msg.width * channels
    step = msg.step or row
    if step < row or len(msg.data) != step * msg.height:
        raise BadFrame(
            "bad_size",
            f"malformed image: {msg.width}x{msg.height} {msg.encoding} needs "
            f"{row * msg.height} bytes (step {step}), got {len(msg.data)}",
        )
    pixels = np.frombuffer(msg.data, np.uint8).reshape(msg.height, step)[:, :row]
    pixels = pixels.reshape(msg.height, msg.width, channels)
    if channels == 1:
        return np.repeat(pixels, 3, axis=2)
    if encoding in ("rgb8", "rgba8"):
        return np.ascontiguousarray(pixels[:, :, 2::-1])
    bgr = pixels[:, :, :3]
    if copy:
        return np.array(bgr, order="C")
    return bgr if step == row and channels == 3 else np.ascontiguousarray(bgr)


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
    """Decode a JPEG/PNG CompressedImage to a BGR ``uint8`` (height, width, 3) array (needs
    OpenCV).

    Raises:
        DroneError: OpenCV is not installed.
        BadFrame: empty data, or bytes OpenCV cannot decode.
    """
    if not msg.data:
        raise BadFrame("empty", "compressed image with empty data")
    cv2 = jpeg_decoder()
    image = cv2.imdecode(np.frombuffer(msg.data, dtype=np.uint8), cv2.IMREAD_COLOR)
    if image is None or image.size == 0:
        raise BadFrame("undecodable", f"cannot decode a {len(msg.data)}-byte {msg.format!r} image")
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
        data=memoryview(np.ascontiguousarray(bgr).reshape(-1)),  # type: ignore[arg-type]  # numpy types __buffer__ from 3.12
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
