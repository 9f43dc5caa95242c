"""The paper's error terms: signs, units, float (not integer) division and the person bound."""

from __future__ import annotations

import pytest

from dronewrapper.msgs.vision import BoundingBox2D, Detection2D
from dronewrapper_controller.errors import (
    blob_radius,
    centre_errors,
    colour_forward_error,
    follow_color_errors,
    follow_person_errors,
    person_forward_error,
)


def det(cx: float, cy: float, w: float, h: float, radius: float = 0.0) -> Detection2D:
    box = BoundingBox2D.at(cx, cy, w, h)
    return Detection2D(bbox=box, circle_radius=radius)


def test_centre_errors_signs_match_flu():
    # object up-left of centre in a 320x240 image -> climb (e_z > 0) and turn left (e_yaw > 0)
    e_z, e_yaw = centre_errors(100, 60, 320, 240, 320)
    assert e_z == pytest.approx(60) and e_yaw == pytest.approx(60)
    e_z, e_yaw = centre_errors(260, 200, 320, 240, 320)
    assert e_z == pytest.approx(-80) and e_yaw == pytest.approx(-100)
    assert centre_errors(160, 120, 320, 240, 320) == (0.0, 0.0)


def test_centre_errors_are_in_reference_pixels():
    """The same bearing at 640 px wide gives the same error as at 320 px."""
    assert centre_errors(200, 200, 640, 480, 320) == pytest.approx(
        centre_errors(100, 100, 320, 240, 320)
    )


def test_colour_forward_error_is_a_float_ratio():
    # the original's int division gave (14 - 10) // 10 == 0 -> no forward control at all
    assert colour_forward_error(14, 320, 10, 320) == pytest.approx(0.4)
    assert colour_forward_error(5, 320, 10, 320) == pytest.approx(-0.5)
    assert colour_forward_error(10, 320, 10, 320) == 0.0
    assert colour_forward_error(28, 640, 10, 320) == pytest.approx(0.4)  # scaled to ref px


def test_colour_forward_error_rejects_bad_reference():
    with pytest.raises(ValueError):
        colour_forward_error(10, 320, 0, 320)
    with pytest.raises(ValueError):
        colour_forward_error(10, 0, 10, 320)


def test_person_forward_error_is_the_paper_formula_when_in_range():
    total = 320 * 240
    assert person_forward_error(total / 20, total, 20, 50) == pytest.approx(0.0)
    assert person_forward_error(total / 25, total, 20, 50) == pytest.approx(5.0)  # a bit far
    assert person_forward_error(total / 4, total, 20, 50) == pytest.approx(-16.0)  # too close


def test_person_forward_error_is_bounded_for_a_far_person():
    """A 20x20 px person: the original's error was 172 (-> 8.6 m/s); ours stops at the bound."""
    total = 320 * 240
    assert person_forward_error(400, total, 20, 10) == pytest.approx(10.0)
    assert person_forward_error(1, total, 20, 10) == pytest.approx(10.0)
    assert person_forward_error(0, total, 20, 10) == pytest.approx(10.0)
    assert person_forward_error(total, total, 20, 10) == pytest.approx(-10.0)


def test_blob_radius_falls_back_to_box():
    assert blob_radius(det(0, 0, 30, 20, radius=12)) == 12
    assert blob_radius(det(0, 0, 30, 20)) == 15


def test_follow_color_errors_combine_terms():
    e = follow_color_errors(det(200, 100, 20, 20, radius=5), 320, 240, 10, 320)
    assert (e.x, e.z, e.yaw) == pytest.approx((-0.5, 20, -40))


def test_follow_person_errors_combine_terms():
    e = follow_person_errors(det(160, 150, 40, 96), 320, 240, 20, 10, 320)
    assert (e.x, e.z, e.yaw) == pytest.approx((0.0, -30, 0))
