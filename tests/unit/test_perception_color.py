"""Colour filter: the paper's red ranges, hue wrap, rejection of near colours, geometry."""

from __future__ import annotations

import math

import cv2
import numpy as np
import pytest

from dronewrapper_perception.color_filter import (
    PRESETS,
    RED,
    ColorRange,
    color_mask,
    degrees_to_opencv_hue,
    detect_color,
    preset,
    scaled_kernel,
)


def hsv_colour(h: int, s: int = 255, v: int = 230) -> tuple[int, int, int]:
    """BGR of an OpenCV HSV colour (hue 0..179)."""
    pixel = cv2.cvtColor(np.uint8([[[h, s, v]]]), cv2.COLOR_HSV2BGR)[0, 0]
    return tuple(int(c) for c in pixel)  # type: ignore[return-value]


def scene(background=(90, 120, 60)) -> np.ndarray:
    """A 640x480 green-grey background with some texture (no red)."""
    rng = np.random.default_rng(1)
    img = np.empty((480, 640, 3), np.uint8)
    img[:] = background
    noise = rng.integers(-10, 10, img.shape)
    return np.clip(img.astype(int) + noise, 0, 255).astype(np.uint8)


def test_red_preset_is_the_papers_two_ranges():
    assert [(r.h_min, r.h_max, r.s_min, r.s_max, r.v_min, r.v_max) for r in RED] == [
        (0, 5, 70, 255, 50, 255),
        (170, 179, 70, 255, 50, 255),
    ]
    # the paper's degrees 0-10 and 340-359 convert to the same OpenCV hues
    assert ColorRange.from_degrees(0, 10) == RED[0]
    assert ColorRange.from_degrees(340, 359) == RED[1]
    assert degrees_to_opencv_hue(360) == 179


@pytest.mark.parametrize("scale", [1.0, 0.5, 0.25])
def test_red_disc_found_with_centroid_and_radius(scale):
    """The same geometry, in input pixels, at full resolution and on a shrunk image."""
    img = scene()
    cv2.circle(img, (400, 180), 40, (20, 20, 220), -1)
    blobs = detect_color(img, RED, scale=scale)
    assert len(blobs) == 1
    blob = blobs[0]
    assert blob.centroid_xy == pytest.approx((400, 180), abs=1.0)
    assert blob.radius_px == pytest.approx(40, abs=3.0)
    assert blob.area_px == pytest.approx(math.pi * 40**2, rel=0.1)
    x1, y1, x2, y2 = blob.bbox_xyxy
    assert (x1, y1) == pytest.approx((360, 140), abs=3) and (x2, y2) == pytest.approx(
        (441, 221), abs=3
    )


def test_largest_blob_first():
    img = scene()
    cv2.circle(img, (100, 100), 15, (0, 0, 230), -1)
    cv2.circle(img, (500, 300), 50, (0, 0, 230), -1)
    blobs = detect_color(img, RED)
    assert [round(b.centroid_xy[0]) for b in blobs] == [500, 100]


def test_hue_wrap_red_straddling_zero_is_one_blob():
    """Half the disc has hue 176, half hue 2: both sides of the wrap are red."""
    img = scene()
    cv2.circle(img, (320, 240), 60, hsv_colour(176), -1)
    cv2.rectangle(img, (320, 170), (390, 310), (0, 0, 0), -1)
    cv2.ellipse(img, (320, 240), (60, 60), 0, -90, 90, hsv_colour(2), -1)
    blobs = detect_color(img, RED)
    assert len(blobs) == 1
    assert blobs[0].centroid_xy == pytest.approx((320, 240), abs=2.0)
    assert blobs[0].radius_px == pytest.approx(60, abs=3.0)
    # each half alone only covers half: the wrap really joins them
    lower_only = detect_color(img, RED[:1])
    assert lower_only[0].area_px < 0.6 * blobs[0].area_px


def test_wrapping_range_equals_two_ranges():
    img = scene()
    cv2.circle(img, (200, 200), 30, hsv_colour(175), -1)
    cv2.circle(img, (450, 300), 30, hsv_colour(3), -1)
    wrapped = ColorRange(170, 5)
    assert wrapped.wraps
    assert np.array_equal(color_mask(img, [wrapped]), color_mask(img, RED))
    assert len(detect_color(img, [wrapped])) == 2


def test_no_target_frame_gives_nothing():
    assert detect_color(scene(), RED) == []
    assert detect_color(np.zeros((480, 640, 3), np.uint8), RED) == []
    assert detect_color(np.full((480, 640, 3), 255, np.uint8), RED) == []


@pytest.mark.parametrize(
    "bgr",
    [
        (0, 140, 255),  # orange (hue 16)
        (0, 200, 255),  # yellow-orange
        (203, 192, 255),  # pink (low saturation)
        (180, 105, 255),  # hot pink (hue 165)
        (150, 150, 200),  # pale pink (S 63 < 70)
    ],
)
@pytest.mark.parametrize("scale", [1.0, 0.5])
def test_near_colours_rejected(bgr, scale):
    img = scene()
    cv2.circle(img, (320, 240), 50, bgr, -1)
    hsv = cv2.cvtColor(np.uint8([[bgr]]), cv2.COLOR_BGR2HSV)[0, 0]
    assert detect_color(img, RED, scale=scale) == [], f"HSV {hsv.tolist()} must not count as red"


@pytest.mark.parametrize("scale", [1.0, 0.5])
def test_small_specks_are_noise(scale):
    img = scene()
    cv2.circle(img, (100, 100), 2, (0, 0, 230), -1)
    assert detect_color(img, RED, min_area_px=20, scale=scale) == []
    cv2.circle(img, (300, 300), 6, (0, 0, 230), -1)  # about 113 px²: kept at either scale
    (blob,) = detect_color(img, RED, min_area_px=20, scale=scale)
    assert blob.centroid_xy == pytest.approx((300, 300), abs=1.0)


def test_scaled_blob_maps_pixel_centres_back():
    """A one-pixel-wide feature at small pixel i covers input pixels 2i and 2i+1: centre 2i+0.5."""
    img = scene()
    img[100:104, 200:208] = (0, 0, 230)  # 8x4 px box: centre (203.5, 101.5), edges 200..208
    (blob,) = detect_color(img, RED, blur=0, min_area_px=0, scale=0.5)
    assert blob.bbox_xyxy == pytest.approx((200, 100, 208, 104))
    assert blob.centroid_xy == pytest.approx((203.5, 101.5), abs=0.01)


def test_scaled_kernel_stays_odd():
    assert [scaled_kernel(11, s) for s in (1.0, 0.5, 0.25, 0.1)] == [11, 5, 3, 0]
    assert scaled_kernel(0, 0.5) == 0 and scaled_kernel(1, 0.5) == 1
    for bad in (0.0, -0.5, 1.5, float("nan")):
        with pytest.raises(ValueError, match="scale"):
            detect_color(scene(), RED, scale=bad)


def test_presets_and_validation():
    img = scene((40, 40, 40))
    cv2.circle(img, (300, 200), 30, hsv_colour(60), -1)
    assert len(detect_color(img, preset("green"))) == 1
    assert detect_color(img, RED) == []
    assert set(PRESETS) >= {"red", "green", "blue", "yellow"}
    with pytest.raises(ValueError, match="unknown colour preset"):
        preset("mauve")
    with pytest.raises(ValueError):
        ColorRange(0, 200)
    with pytest.raises(ValueError):
        detect_color(np.zeros((10, 10), np.uint8), RED)
    with pytest.raises(ValueError):
        detect_color(img, RED, blur=4)
