"""Settings suggested for a latency target (bench/suggest.py), from given measurements."""

from __future__ import annotations

import sys

import pytest

from support import REPO

sys.path.insert(0, str(REPO))  # bench/ holds scripts at the repository root, not a package

from bench.suggest import DetectorSpeed, estimate, suggest

MS = 1e-3
NANO_416 = DetectorSpeed(416, 17 * MS, 30 * MS)
NANO_320 = DetectorSpeed(320, 10 * MS, 18 * MS)
FIGURES = {"render_s": 4 * MS, "middleware_p50_s": 3 * MS, "middleware_p99_s": 10 * MS}


def test_estimate_a_detector_with_time_to_spare_takes_frames_on_arrival():
    est = estimate(NANO_416, 10, camera_fps=30, **FIGURES)
    assert not est.saturated
    assert est.cpu_cores == pytest.approx(0.17)
    assert est.p50_ms == pytest.approx(4 + 3 + 17)
    assert est.p99_ms == pytest.approx(4 + 10 + 30)
    tight = estimate(DetectorSpeed(416, 25 * MS, 45 * MS), 30, camera_fps=30, **FIGURES)
    assert not tight.saturated  # 0.75 of a core
    assert tight.p99_ms == pytest.approx(4 + 10 + 45 + (45 - 1000 / 30))  # a slow one delays


def test_estimate_busy_detector_makes_frames_wait_for_it():
    slow = DetectorSpeed(416, 40 * MS, 60 * MS)
    est = estimate(slow, 30, camera_fps=30, **FIGURES)
    assert est.saturated
    assert est.fps == pytest.approx(25)  # cannot run faster than it detects
    assert est.p50_ms == pytest.approx(4 + 3 + 40 + 20)
    assert est.p99_ms == pytest.approx(4 + 10 + 60 + 60)
    assert not estimate(NANO_416, 30, camera_fps=30, **FIGURES).saturated  # 0.51 of a core


def test_largest_input_that_meets_the_target_at_the_cpu_budget():
    got = suggest(45, [NANO_320, NANO_416], cpu_budget=0.5, **FIGURES)
    assert got.meets_target
    assert got.best.input_size == 416
    assert got.best.fps == 29  # floor(0.5 core / 17 ms)
    assert "416 px at 29 fps" in got.reason
    tighter = suggest(22, [NANO_320, NANO_416], cpu_budget=0.5, **FIGURES)
    assert tighter.meets_target and tighter.best.input_size == 320
    assert [c.input_size for c in tighter.candidates] == [416, 320]


def test_a_small_cpu_budget_lowers_the_rate_never_below_min_fps():
    got = suggest(60, [NANO_416], cpu_budget=0.1, min_fps=5, **FIGURES)
    assert got.best.fps == 5  # 0.1 / 0.017 = 5.9 -> 5
    tiny = suggest(60, [NANO_416], cpu_budget=0.02, min_fps=5, **FIGURES)
    assert tiny.best.fps == 5 and "more CPU than the budget" in tiny.reason


def test_an_unreachable_target_says_so_with_the_fastest_setting():
    got = suggest(10, [NANO_416, NANO_320], **FIGURES)
    assert not got.meets_target
    assert got.best.input_size == 320
    assert "no setting meets 10 ms" in got.reason


def test_bad_inputs_are_refused():
    with pytest.raises(ValueError, match="no detector speeds"):
        suggest(50, [], **FIGURES)
    with pytest.raises(ValueError, match="target_ms"):
        suggest(float("nan"), [NANO_416], **FIGURES)
    with pytest.raises(ValueError, match="bad detector speed"):
        suggest(50, [DetectorSpeed(416, 0.0, 0.0)], **FIGURES)
