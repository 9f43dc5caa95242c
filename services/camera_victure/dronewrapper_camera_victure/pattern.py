"""The test pattern: colour bars that move, the frame counter and the time, machine-readable.

The counter is also written as 32 black/white blocks across the top band (most significant bit
first), so a test can read it back from a received frame, raw or JPEG, and check that no frame
came twice or out of order.
"""

from __future__ import annotations

import time

import cv2
import numpy as np

COUNTER_BITS = 32
BAND_PX = 16
"""Height of the top band that carries the counter blocks (px)."""

_BARS = np.array(
    [
        (255, 255, 255),
        (0, 255, 255),
        (255, 255, 0),
        (0, 255, 0),
        (255, 0, 255),
        (0, 0, 255),
        (255, 0, 0),
        (0, 0, 0),
    ],
    dtype=np.uint8,
)


def render_pattern(width: int, height: int, counter: int, stamp: float) -> np.ndarray:
    """A ``height x width`` bgr8 frame for frame number ``counter`` taken at ``stamp`` (epoch s).

    Raises:
        ValueError: a frame too small to hold the counter blocks (< 64 x 32 px).
    """
    if width < 2 * COUNTER_BITS or height < 2 * BAND_PX:
        raise ValueError(f"test pattern {width}x{height} too small (>= 64x32 px)")
    columns = (np.arange(width) * len(_BARS) // width + counter) % len(_BARS)
    frame = np.ascontiguousarray(np.broadcast_to(_BARS[columns], (height, width, 3)))
    block = width // COUNTER_BITS
    frame[:BAND_PX] = 128
    for bit in range(COUNTER_BITS):
        on = (counter >> (COUNTER_BITS - 1 - bit)) & 1
        frame[:BAND_PX, bit * block : (bit + 1) * block] = 255 if on else 0
    clock = time.strftime("%H:%M:%S", time.gmtime(stamp)) + f".{int(stamp * 1000) % 1000:03d}"
    scale = max(0.4, height / 480)
    y = BAND_PX + int(40 * scale)
    for text in (f"frame {counter}", f"{clock} UTC"):
        cv2.putText(frame, text, (8, y), cv2.FONT_HERSHEY_SIMPLEX, scale, (0, 0, 0), 4)
        cv2.putText(frame, text, (8, y), cv2.FONT_HERSHEY_SIMPLEX, scale, (255, 255, 255), 1)
        y += int(40 * scale)
    return frame


def read_counter(frame: np.ndarray) -> int:
    """The frame counter written in ``frame``'s top band (survives JPEG and resizing by
    whole factors)."""
    width = frame.shape[1]
    block = width // COUNTER_BITS
    band = frame[: BAND_PX // 2]
    value = 0
    for bit in range(COUNTER_BITS):
        centre = band[:, bit * block + block // 4 : bit * block + 3 * block // 4]
        value = (value << 1) | int(centre.mean() > 127)
    return value
