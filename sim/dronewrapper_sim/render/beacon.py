"""Drawing the red beacon: a shaded sphere of the projected radius, with sub-pixel accuracy."""

from __future__ import annotations

import math

import cv2
import numpy as np

__all__ = ["draw_beacon", "sphere_radius_px"]

_SHIFT = 4  # sub-pixel bits for OpenCV drawing
_ONE = 1 << _SHIFT


def sphere_radius_px(focal_px: float, radius_m: float, distance_m: float) -> float:
    """Apparent radius (px) of a sphere of ``radius_m`` whose centre is ``distance_m`` away."""
    if distance_m <= radius_m:
        return math.inf
    return focal_px * radius_m / math.sqrt(distance_m**2 - radius_m**2)


def _fixed(v: float) -> int:
    return round(v * _ONE)


def draw_beacon(
    image: np.ndarray,
    center_px: tuple[float, float],
    radius_px: float,
    color_bgr: tuple[int, int, int],
) -> None:
    """Draw a sphere lit from the upper left: a dark rim, lighter inner discs, a soft highlight.

    Every shade keeps the hue and enough saturation to pass a red HSV filter.
    """
    h, w = image.shape[:2]
    limit = 4.0 * (w + h)
    u, v = center_px
    if not (math.isfinite(u) and math.isfinite(v)) or radius_px <= 0:
        return
    if u + radius_px < 0 or v + radius_px < 0 or u - radius_px > w or v - radius_px > h:
        return
    radius_px = min(radius_px, limit)
    color = np.array(color_bgr, dtype=float)
    shades = (
        (1.00, 0.0, 0.55),  # (radius fraction, offset fraction toward the light, brightness)
        (0.86, 0.10, 0.72),
        (0.68, 0.20, 0.88),
        (0.48, 0.30, 1.00),
    )
    light = np.array([-0.55, -0.65])
    light /= np.linalg.norm(light)
    for frac, offset, bright in shades:
        if frac < 1.0 and radius_px * frac < 1.5:
            break
        cu = u + light[0] * offset * radius_px
        cv_ = v + light[1] * offset * radius_px
        shade = tuple(float(c) for c in np.clip(color * bright, 0, 255))
        cv2.circle(
            image,
            (_fixed(cu), _fixed(cv_)),
            max(1, _fixed(radius_px * frac)),
            shade,
            -1,
            cv2.LINE_AA,
            _SHIFT,
        )
    if radius_px >= 4.0:  # specular highlight, pinkish so it stays red-ish
        spec = np.clip(color * 1.0 + np.array([90.0, 90.0, 40.0]), 0, 255)
        cv2.circle(
            image,
            (_fixed(u + light[0] * 0.45 * radius_px), _fixed(v + light[1] * 0.45 * radius_px)),
            max(1, _fixed(radius_px * 0.16)),
            tuple(float(c) for c in spec),
            -1,
            cv2.LINE_AA,
            _SHIFT,
        )
