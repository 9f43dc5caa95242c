"""Colour-blob detection: the paper's follow-colour pipeline, pure (arrays in, blobs out).

Pipeline (DroneWrapper paper / seed code section 4.2, with its bugs fixed):
Gaussian blur -> BGR to HSV -> ``inRange`` for every :class:`ColorRange` (OR-ed, so the red hue
that wraps around 0 is two ranges) -> external contours -> for each contour, largest first:
centroid from the image moments, minimum enclosing circle, bounding box.

Units: every coordinate is in pixels of the input image (origin top-left, x right, y down).
With ``scale < 1`` the image is first shrunk by area averaging (``INTER_AREA``, itself a low-pass
filter) and the pipeline runs on the small image; blur kernel and minimum area, given in input
pixels, are scaled down with it and the blobs are mapped back to input pixels. At 0.5 the work is
a quarter (640x480: about 0.9 ms instead of 4 ms on one core) for about a pixel of precision.
HSV values are OpenCV's: hue 0..179 (= degrees / 2; hue wraps, 179 is next to 0), saturation
and value 0..255. The paper's tables give hue in degrees 0..359; use
:meth:`ColorRange.from_degrees` for those.

The original also thresholded the grey conversion *of the HSV image* at 150 (an accidental extra
condition on a mix of H, S and V); here the saturation/value bounds of each range say what they
mean instead.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence
from dataclasses import dataclass

import cv2
import numpy as np

HUE_MAX = 179
"""Largest OpenCV 8-bit hue value (OpenCV hue = degrees / 2)."""


@dataclass(frozen=True)
class ColorRange:
    """An HSV box in OpenCV units (hue 0..179, saturation 0..255, value 0..255), inclusive.

    A range whose ``h_min`` is greater than ``h_max`` wraps through hue 0: ``h_min=170,
    h_max=5`` means 170..179 and 0..5.
    """

    h_min: int
    h_max: int
    s_min: int = 70
    s_max: int = 255
    v_min: int = 50
    v_max: int = 255

    def __post_init__(self) -> None:
        for name in ("h_min", "h_max"):
            value = getattr(self, name)
            if not 0 <= value <= HUE_MAX:
                raise ValueError(f"{name}={value} must be an OpenCV hue in 0..{HUE_MAX}")
        for name in ("s_min", "s_max", "v_min", "v_max"):
            value = getattr(self, name)
            if not 0 <= value <= 255:
                raise ValueError(f"{name}={value} must be in 0..255")
        if self.s_min > self.s_max or self.v_min > self.v_max:
            raise ValueError(f"{self}: a minimum is above its maximum")

    @classmethod
    def from_degrees(
        cls,
        h_min_deg: float,
        h_max_deg: float,
        s_min: int = 70,
        s_max: int = 255,
        v_min: int = 50,
        v_max: int = 255,
    ) -> ColorRange:
        """A range from hue in degrees (0..360), as the paper's tables give it."""
        for deg in (h_min_deg, h_max_deg):
            if not 0 <= deg <= 360:
                raise ValueError(f"hue {deg} deg must be in 0..360")
        return cls(
            degrees_to_opencv_hue(h_min_deg),
            degrees_to_opencv_hue(h_max_deg),
            s_min,
            s_max,
            v_min,
            v_max,
        )

    @property
    def wraps(self) -> bool:
        """True when the hue interval passes through 0 (e.g. 170..5)."""
        return self.h_min > self.h_max

    def bounds(self) -> list[tuple[np.ndarray, np.ndarray]]:
        """The ``(lower, upper)`` arrays for ``cv2.inRange``: two when the hue wraps."""
        hue_spans = (
            [(self.h_min, HUE_MAX), (0, self.h_max)] if self.wraps else [(self.h_min, self.h_max)]
        )
        return [
            (
                np.array([lo, self.s_min, self.v_min], np.uint8),
                np.array([hi, self.s_max, self.v_max], np.uint8),
            )
            for lo, hi in hue_spans
        ]


def degrees_to_opencv_hue(degrees: float) -> int:
    """Hue in degrees (0..360) to OpenCV's 8-bit hue (0..179); 360 and 359 map to 179."""
    return min(HUE_MAX, math.floor(degrees / 2.0))


PRESETS: dict[str, tuple[ColorRange, ...]] = {
    # The paper's red: OpenCV hue 0-5 and 170-179 (degrees 0-10 and 340-359), S 70-255, V 50-255.
    "red": (ColorRange(0, 5, 70, 255, 50, 255), ColorRange(170, 179, 70, 255, 50, 255)),
    "green": (ColorRange(40, 80, 70, 255, 50, 255),),
    "blue": (ColorRange(100, 130, 100, 255, 50, 255),),
    "yellow": (ColorRange(22, 33, 100, 255, 80, 255),),
}
"""Named colour presets (tuples of ranges, OR-ed)."""

RED = PRESETS["red"]


def preset(name: str) -> tuple[ColorRange, ...]:
    """The ranges of a named preset; ValueError naming the known presets otherwise."""
    try:
        return PRESETS[name]
    except KeyError:
        known = ", ".join(sorted(PRESETS))
        raise ValueError(f"unknown colour preset {name!r} (known: {known})") from None


@dataclass(frozen=True)
class ColorBlob:
    """One connected colour region, in pixels of the input image.

    Attributes:
        centroid_xy: centre of mass of the region (image moments), px.
        radius_px: radius of the minimum enclosing circle, px.
        area_px: contour area, px².
        bbox_xyxy: axis-aligned bounding box (left, top, right, bottom), px; right/bottom are
            exclusive (``x + w``).
        circle_center_xy: centre of the minimum enclosing circle, px.
    """

    centroid_xy: tuple[float, float]
    radius_px: float
    area_px: float
    bbox_xyxy: tuple[float, float, float, float]
    circle_center_xy: tuple[float, float] = (0.0, 0.0)

    def scaled(self, fx: float, fy: float) -> ColorBlob:
        """This blob found in an image shrunk by ``1/fx`` x ``1/fy``, in the full image's px.

        Pixel centres map as ``(i + 0.5) * f - 0.5``; box edges (exclusive) as ``x * f``; the
        radius by the mean factor; the area by ``fx * fy``.
        """

        def centre(xy: tuple[float, float]) -> tuple[float, float]:
            return ((xy[0] + 0.5) * fx - 0.5, (xy[1] + 0.5) * fy - 0.5)

        left, top, right, bottom = self.bbox_xyxy
        return ColorBlob(
            centroid_xy=centre(self.centroid_xy),
            radius_px=self.radius_px * (fx + fy) / 2.0,
            area_px=self.area_px * fx * fy,
            bbox_xyxy=(left * fx, top * fy, right * fx, bottom * fy),
            circle_center_xy=centre(self.circle_center_xy),
        )


def color_mask(bgr: np.ndarray, ranges: Iterable[ColorRange], *, blur: int = 11) -> np.ndarray:
    """The binary mask (uint8 0/255, same height/width) of pixels inside any of ``ranges``.

    ``blur`` is the Gaussian kernel size in px (odd; 0 or 1 = no blur).
    """
    _check_image(bgr)
    if blur < 0 or (blur > 1 and blur % 2 == 0):
        raise ValueError(f"blur={blur} must be 0, 1 or an odd kernel size in px")
    image = cv2.GaussianBlur(bgr, (blur, blur), 0) if blur > 1 else bgr
    hsv = cv2.cvtColor(image, cv2.COLOR_BGR2HSV)
    mask: np.ndarray | None = None
    for colour_range in ranges:
        for lower, upper in colour_range.bounds():
            part = cv2.inRange(hsv, lower, upper)
            mask = part if mask is None else cv2.bitwise_or(mask, part)
    if mask is None:
        raise ValueError("no colour ranges given")
    return mask


def blobs_from_mask(mask: np.ndarray, *, min_area_px: float = 20.0) -> list[ColorBlob]:
    """The external contours of a binary mask as blobs, largest area first."""
    contours, _ = cv2.findContours(mask, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_SIMPLE)
    blobs: list[ColorBlob] = []
    for contour in contours:
        area = float(cv2.contourArea(contour))
        if area < min_area_px:
            continue
        moments = cv2.moments(contour)
        x, y, w, h = cv2.boundingRect(contour)
        if moments["m00"] > 0:
            centroid = (moments["m10"] / moments["m00"], moments["m01"] / moments["m00"])
        else:
            centroid = (x + w / 2.0, y + h / 2.0)
        (ccx, ccy), radius = cv2.minEnclosingCircle(contour)
        blobs.append(
            ColorBlob(
                centroid_xy=(float(centroid[0]), float(centroid[1])),
                radius_px=float(radius),
                area_px=area,
                bbox_xyxy=(float(x), float(y), float(x + w), float(y + h)),
                circle_center_xy=(float(ccx), float(ccy)),
            )
        )
    blobs.sort(key=lambda b: b.area_px, reverse=True)
    return blobs


def detect_color(
    bgr: np.ndarray,
    ranges: Sequence[ColorRange] = RED,
    *,
    blur: int = 11,
    min_area_px: float = 20.0,
    scale: float = 1.0,
) -> list[ColorBlob]:
    """Colour blobs in a BGR image, largest first (the first one is the paper's target).

    Args:
        bgr: HxWx3 uint8 image in OpenCV (BGR) channel order.
        ranges: HSV ranges (OpenCV units), OR-ed; default the paper's red.
        blur: Gaussian blur kernel size in px of ``bgr`` (odd; 0 = none).
        min_area_px: contours smaller than this (px² of ``bgr``) are noise and dropped.
        scale: analysis scale in (0, 1]: the pipeline runs on the image shrunk by this factor
            (1 = full resolution, the paper's pipeline exactly); blobs are in ``bgr`` pixels.
    """
    if not (isinstance(scale, (int, float)) and 0.0 < scale <= 1.0):
        raise ValueError(f"scale={scale!r} must be in (0, 1]")
    if scale == 1.0:
        return blobs_from_mask(color_mask(bgr, ranges, blur=blur), min_area_px=min_area_px)
    _check_image(bgr)
    height, width = bgr.shape[:2]
    size = (max(1, round(width * scale)), max(1, round(height * scale)))
    small = cv2.resize(bgr, size, interpolation=cv2.INTER_AREA)
    fx, fy = width / size[0], height / size[1]
    blobs = blobs_from_mask(
        color_mask(small, ranges, blur=scaled_kernel(blur, scale)),
        min_area_px=min_area_px / (fx * fy),
    )
    return [blob.scaled(fx, fy) for blob in blobs]


def scaled_kernel(blur: int, scale: float) -> int:
    """A blur kernel size (odd px, or 0) for an image shrunk by ``scale``: ``blur * scale``
    truncated, made odd; 0 when that is 1 px (shrinking by area averaging already blurs)."""
    if blur <= 1:
        return blur
    size = int(blur * scale) | 1
    return size if size > 1 else 0


def _check_image(bgr: np.ndarray) -> None:
    if not isinstance(bgr, np.ndarray) or bgr.dtype != np.uint8:
        raise ValueError("image must be a uint8 numpy array")
    if bgr.ndim != 3 or bgr.shape[2] != 3 or bgr.shape[0] == 0 or bgr.shape[1] == 0:
        raise ValueError(f"image must be HxWx3 BGR, got shape {bgr.shape}")
