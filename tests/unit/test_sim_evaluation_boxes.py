"""The ground-truth labelling of detections (dronewrapper_sim.evaluation.boxes): overlap and
which person a detected box is."""

import pytest

from dronewrapper_sim.evaluation.boxes import iou, owner


def test_iou_of_boxes():
    assert iou((0, 0, 10, 10), (0, 0, 10, 10)) == 1.0
    assert iou((0, 0, 10, 10), (5, 0, 15, 10)) == pytest.approx(50 / 150)
    assert iou((0, 0, 10, 10), (20, 20, 30, 30)) == 0.0
    assert iou((0, 0, 0, 0), (0, 0, 0, 0)) == 0.0  # no area: no overlap to speak of


def test_owner_is_the_best_overlap_and_the_nearer_in_a_tie():
    people = {"far": ((0, 0, 10, 10), 9.0), "near": ((0.5, 0, 10.5, 10), 3.0)}
    assert owner((0, 0, 10, 10), people) == "near"  # 1.0 vs 0.90: within 0.1 of the best
    assert owner((0, 0, 10, 10), {"a": ((0, 0, 10, 10), 9.0), "b": ((5, 0, 15, 10), 1.0)}) == "a"
    assert owner((50, 50, 60, 60), people) is None  # overlaps nobody enough
