"""Follow quality from ground truth: bearing, elevation, distance and the flight summary."""

from __future__ import annotations

import math

import pytest

from dronewrapper.rotations import wrap_pi
from dronewrapper_sim.evaluation.metrics import (
    FollowSample,
    bearing_error,
    elevation_error,
    summarize,
)


def test_bearing_error_signs_and_wrap():
    assert bearing_error((0, 0), 0.0, (5, 0)) == pytest.approx(0.0)
    assert bearing_error((0, 0), 0.0, (5, 5)) == pytest.approx(math.pi / 4)  # left: +
    assert bearing_error((0, 0), math.pi / 2, (5, 0)) == pytest.approx(-math.pi / 2)
    assert bearing_error((0, 0), math.radians(179), (-5, -0.1)) == pytest.approx(
        math.radians(2.146), abs=1e-3
    )
    assert wrap_pi(3 * math.pi) == pytest.approx(-math.pi)


def test_elevation_error():
    assert elevation_error((0, 0, 2), (5, 0, 2)) == pytest.approx(0.0)
    assert elevation_error((0, 0, 2), (5, 0, 7)) == pytest.approx(math.pi / 4)


def sample(t, x, yaw=0.0, target=(5.0, 0.0, 2.0), state="tracking", visible=True, others=None):
    return FollowSample(
        t=t,
        vehicle=(x, 0.0, 2.0),
        yaw=yaw,
        target=target,
        others=others or {},
        state=state,
        target_visible=visible,
    )


def test_summary_acquisition_centring_and_distance():
    samples = [sample(0.0, 0.0, state="takeoff", visible=False)]
    samples += [sample(1.0 + 0.1 * k, 0.0, yaw=0.5, visible=False) for k in range(10)]  # turning
    samples += [sample(2.0 + 0.1 * k, 1.0) for k in range(80)]  # centred at 4 m
    samples += [sample(10.0 + 0.1 * k, 1.0, yaw=0.5) for k in range(20)]  # off-centre
    s = summarize(samples, intended_distance=5.0, distance_tolerance=1.5)
    assert s.time_to_acquire == pytest.approx(1.0)
    assert s.centred_share == pytest.approx(0.8)
    assert s.distance_mean == pytest.approx(1.0)
    assert s.distance_share == 1.0
    assert s.visible_share == 1.0
    assert s.duration == pytest.approx(10.0 + 1.9 - 1.0)


def test_summary_never_acquired():
    samples = [sample(0.1 * k, 0.0, yaw=1.0, visible=False, state="search") for k in range(10)]
    s = summarize(samples, intended_distance=5.0)
    assert s.time_to_acquire == math.inf and s.centred_share == 0.0


def test_summary_without_flight():
    assert summarize([], intended_distance=5.0).samples == 0


def test_closest_to_axis_names_the_object_in_view():
    s = sample(0.0, 0.0, target=(5.0, 3.0, 2.0), others={"person1": (5.0, 0.2, 2.0)})
    assert s.closest_to_axis() == "person1"
    s = sample(0.0, 0.0, target=(5.0, 0.1, 2.0), others={"person1": (5.0, -2.0, 2.0)})
    assert s.closest_to_axis() == "target"


def test_intended_distances_from_the_camera_model():
    from dronewrapper_sim.evaluation.metrics import (
        colour_intended_distance,
        focal_px,
        person_intended_distance,
    )

    assert focal_px(640, math.radians(90)) == pytest.approx(320)
    # 0.3 m sphere, 90 deg camera (f 320 px at 640 px): 16 px radius at 6 m; 8 ref px of 320
    assert colour_intended_distance(8, 320, 640, math.radians(90), 0.3) == pytest.approx(6.0)
    # a 2 m x 0.5 m person filling 1/20 of 640x480: area 15360 px^2 = f^2 * 1 / d^2
    d = person_intended_distance(20, 640, 480, math.radians(90), 2.0, 0.5)
    assert (320 * 2.0 / d) * (320 * 0.5 / d) == pytest.approx(640 * 480 / 20)
