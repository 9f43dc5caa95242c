"""The controller checks every Detections message; a bad one is dropped, never fatal."""

from __future__ import annotations

import math
import re

import msgspec
import pytest

from dronewrapper.msgs.std import Header
from dronewrapper.msgs.vision import (
    BoundingBox2D,
    Detection2D,
    Detections,
    ObjectHypothesis,
    ObjectHypothesisWithPose,
)
from dronewrapper_controller.inputs import DetectionsGate, detections_problem


def frame(stamp: float = 1000.0, x: float = 320.0, size: float = 40.0, score: float = 0.9):
    det = Detection2D(
        id="1",
        bbox=BoundingBox2D.at(x, 240.0, size, size),
        results=[
            ObjectHypothesisWithPose(hypothesis=ObjectHypothesis(class_id="red", score=score))
        ],
    )
    return Detections(
        header=Header(stamp=stamp, frame_id="cam_frontal"),
        detections=[det],
        image_width=640,
        image_height=480,
        target_id="1",
    )


def test_a_good_frame_passes():
    assert detections_problem(frame()) is None
    assert detections_problem(Detections()) is None  # empty: "nothing seen" is valid


@pytest.mark.parametrize(
    ("bad", "named"),
    [
        (frame(stamp=math.inf), "header.stamp"),
        (frame(stamp=math.nan), "header.stamp"),
        (frame(stamp=-1.0), "header.stamp"),
        (frame(x=math.nan), r"detections\[0\].bbox.center.position.x"),
        (frame(size=math.inf), r"detections\[0\].bbox.size_x"),
        (frame(size=-3.0), r"detections\[0\].bbox.size_x must be >= 0"),
        (frame(score=math.nan), r"results\[0\].hypothesis.score"),
    ],
)
def test_non_finite_or_negative_fields_are_named(bad, named):
    problem = detections_problem(bad)
    assert problem is not None
    assert re.search(named, problem), problem


def test_frame_size_bounds():
    big = msgspec.structs.replace(frame(), image_width=10**9)
    assert "image_width" in detections_problem(big)


def test_the_gate_counts_and_drops_bad_frames_and_keeps_the_good_one():
    accepted: list[Detections] = []
    drops: list[tuple[int, str]] = []
    gate = DetectionsGate(accepted.append, lambda n, why: drops.append((n, why)))
    good = frame(stamp=5.0)
    gate(good)
    gate(frame(stamp=math.inf))
    gate(frame(x=math.nan))
    assert accepted == [good]
    assert gate.dropped == 2 and [n for n, _ in drops] == [1, 2]
    assert "header.stamp" in drops[0][1]
