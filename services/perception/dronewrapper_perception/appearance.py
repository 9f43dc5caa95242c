"""Appearance descriptors for tracking: a hue-saturation histogram of a box's inner part.

Pure functions on arrays. The histogram skips a margin of the box (background) and dark or grey
pixels carry hue poorly, so value/saturation are binned too: bins over (H, S) plus a small V
histogram, each smoothed across neighbouring bins, concatenated and L1-normalised. Distances
are Bhattacharyya (0 same, 1 disjoint).
"""

from __future__ import annotations

from collections.abc import Sequence

import cv2
import numpy as np

HIST_BINS = (12, 4)  # hue, saturation
VALUE_BINS = 8


def appearance_histogram(
    bgr: np.ndarray,
    box_xyxy: Sequence[float],
    *,
    margin: tuple[float, float] = (0.2, 0.1),
) -> np.ndarray | None:
    """The normalised colour histogram of the box, or None if the box is (nearly) empty.

    Args:
        bgr: the frame, HxWx3 uint8 BGR.
        box_xyxy: (left, top, right, bottom) in px.
        margin: fraction of the width and height cut from each side (skips background).
    """
    h, w = bgr.shape[:2]
    x1, y1, x2, y2 = box_xyxy
    mx, my = (x2 - x1) * margin[0], (y2 - y1) * margin[1]
    left, right = int(max(0, x1 + mx)), int(min(w, x2 - mx))
    top, bottom = int(max(0, y1 + my)), int(min(h, y2 - my))
    if right - left < 2 or bottom - top < 2:
        return None
    hsv = cv2.cvtColor(bgr[top:bottom, left:right], cv2.COLOR_BGR2HSV)
    hs = _smooth(cv2.calcHist([hsv], [0, 1], None, list(HIST_BINS), [0, 180, 0, 256]), True)
    v = _smooth(cv2.calcHist([hsv], [2], None, [VALUE_BINS], [0, 256]).reshape(-1, 1), False)
    hist = np.concatenate((hs.ravel() / max(hs.sum(), 1.0), v.ravel() / max(v.sum(), 1.0)))
    return (hist / hist.sum()).astype(np.float32)


def _smooth(hist: np.ndarray, circular: bool) -> np.ndarray:
    """Spread each bin 1/4 into its neighbours along axis 0 (hue wraps when ``circular``).

    So two nearly equal colours on either side of a bin edge still look alike.
    """
    if circular:
        before, after = np.roll(hist, 1, axis=0), np.roll(hist, -1, axis=0)
    else:
        pad = np.zeros_like(hist[:1])
        before = np.concatenate((pad, hist[:-1]))
        after = np.concatenate((hist[1:], pad))
    return 0.5 * hist + 0.25 * before + 0.25 * after


def bhattacharyya(a: np.ndarray, b: np.ndarray) -> float:
    """Bhattacharyya distance of two L1-normalised histograms, 0 (same) .. 1 (disjoint)."""
    coefficient = float(np.sum(np.sqrt(np.maximum(a, 0) * np.maximum(b, 0))))
    return float(np.sqrt(max(0.0, 1.0 - min(1.0, coefficient))))
