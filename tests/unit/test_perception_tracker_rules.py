"""Trackers one rule at a time: the paper method's fixed bugs, the tracker choice, and the
building blocks (Hungarian assignment, the box Kalman filter, appearance histograms). Crossings
on synthetic sequences: test_perception_tracking.py."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from dronewrapper_perception.appearance import appearance_histogram, bhattacharyya
from dronewrapper_perception.assignment import INFEASIBLE, assign
from dronewrapper_perception.detection import Detection
from dronewrapper_perception.kalman_filter import BoxKalmanFilter
from dronewrapper_perception.tracking import (
    NoTracker,
    PaperTracker,
    make_tracker,
)


def det_at(cx: float, cy: float, score: float = 0.9, w: float = 60, h: float = 160) -> Detection:
    return Detection((cx - w / 2, cy - h / 2, cx + w / 2, cy + h / 2), score, 0, "person")


# ---------------------------------------------------------------- the paper's method, fixed


def test_paper_fifo_holds_five_centroids():
    tracker = PaperTracker()
    for k in range(7):
        tracker.update([det_at(100 + k, 200)], t=k * 0.1)
    assert len(tracker.fifo) == 5
    assert tracker.fifo_mean() == pytest.approx((104, 200))


def test_paper_first_pick_by_numeric_confidence():
    """The seed compared darknet's string percentages: "9.5" > "87.5"."""
    tracker = PaperTracker()
    result = tracker.update([det_at(100, 200, score=0.095), det_at(400, 200, score=0.875)], 0.0)
    assert result.target_index == 1
    assert max(["9.5", "87.5"]) == "9.5"  # what the string comparison would have picked


def test_paper_distance_uses_y_too():
    """The seed's typo zeroed the y term: a detection far below would have won on x alone."""
    tracker = PaperTracker(gate_px=500)
    for k in range(5):
        tracker.update([det_at(100, 100)], t=k * 0.1)
    result = tracker.update([det_at(105, 400), det_at(130, 105)], t=0.5)
    assert result.target_index == 1


def test_paper_single_detection_is_checked():
    """The seed used any lone detection as the target; a far-away stranger is not the target."""
    tracker = PaperTracker(gate_px=120)
    for k in range(5):
        tracker.update([det_at(100, 100)], t=k * 0.1)
    result = tracker.update([det_at(500, 300)], t=0.5)
    assert result.target_index is None and result.target_id == ""
    near = tracker.update([det_at(110, 100)], t=0.6)
    assert near.target_index == 0


def test_paper_miss_does_not_push_zeros():
    """The seed pushed (0, 0) on a miss, dragging the FIFO mean to the image corner."""
    tracker = PaperTracker(gate_px=200)
    first = None
    for k in range(5):
        first = tracker.update([det_at(300, 200)], t=k * 0.1).target_id
    tracker.update([], t=0.5)
    tracker.update([], t=0.6)
    assert (0.0, 0.0) not in tracker.fifo
    assert tracker.fifo_mean() == pytest.approx((300, 200))
    result = tracker.update([det_at(60, 90, score=0.99), det_at(310, 200, score=0.5)], t=0.7)
    assert result.target_index == 1 and result.target_id == first


def test_paper_forgets_after_loss_and_repicks_by_score():
    tracker = PaperTracker(lost_after_s=1.0)
    old = tracker.update([det_at(300, 200)], t=0.0).target_id
    result = tracker.update([det_at(50, 50, 0.4), det_at(600, 400, 0.8)], t=2.0)
    assert result.target_index == 1 and result.target_id != old


def test_no_tracker_takes_the_first():
    result = NoTracker().update([det_at(1, 1), det_at(2, 2)], 0.0)
    assert result.target_index == 0 and result.track_ids == ("target", "")
    assert NoTracker().update([], 0.0).target_index is None
    with pytest.raises(ValueError):
        make_tracker("magic")


# ---------------------------------------------------------------- building blocks


def test_hungarian_assignment_is_optimal():
    cost = np.array([[4, 1, 3], [2, 0, 5], [3, 2, 2]], float)
    assert assign(cost) == [(0, 1), (1, 0), (2, 2)]  # total 5 (greedy would take 0 first)
    rect = np.array([[1, INFEASIBLE], [INFEASIBLE, INFEASIBLE], [INFEASIBLE, 3]], float)
    assert assign(rect) == [(0, 0), (2, 1)]
    assert assign(np.zeros((0, 3))) == []


def test_kalman_filter_learns_velocity_and_coasts():
    kf = BoxKalmanFilter((100, 200, 50, 100), 0.0)
    for k in range(1, 11):
        kf.predict(k * 0.1)
        kf.update((100 + 50 * k * 0.1, 200, 50, 100))
    assert kf.velocity[0] == pytest.approx(50, abs=8)
    kf.predict(2.0)  # 1 s of coasting
    assert kf.box_cxcywh[0] == pytest.approx(200, abs=10)
    near, far = kf.mahalanobis_sq(np.array([[200, 200, 50, 100], [60, 200, 50, 100]]))
    assert near < 1 < far


def test_appearance_separates_colours():
    img = np.full((240, 320, 3), 128, np.uint8)
    cv2.rectangle(img, (20, 20), (80, 200), (0, 0, 200), -1)
    cv2.rectangle(img, (120, 20), (180, 200), (0, 0, 190), -1)
    cv2.rectangle(img, (220, 20), (280, 200), (200, 60, 0), -1)
    noise = np.random.default_rng(3).normal(0, 6, img.shape)
    img = np.clip(img + noise, 0, 255).astype(np.uint8)  # real pixels vary
    red1 = appearance_histogram(img, (20, 20, 80, 200))
    red2 = appearance_histogram(img, (120, 20, 180, 200))
    blue = appearance_histogram(img, (220, 20, 280, 200))
    assert bhattacharyya(red1, red2) < 0.25 < 0.6 < bhattacharyya(red1, blue)
    assert appearance_histogram(img, (10, 10, 10.5, 10.5)) is None
