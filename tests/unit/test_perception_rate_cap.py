"""Detect at N fps of camera time: which frames the rate cap admits, judged by their stamps."""

from __future__ import annotations

import itertools

import pytest

from dronewrapper_perception.config import Config
from dronewrapper_perception.rate_cap import FrameRateCap


def admitted(cap: FrameRateCap, stamps) -> list[float]:
    return [t for t in stamps if cap.admit(t)]


def test_a_30_fps_camera_capped_at_10_gives_every_third_frame():
    stamps = [k / 30 for k in range(90)]
    kept = admitted(FrameRateCap(10.0), stamps)
    assert len(kept) == 30
    assert all(b - a == pytest.approx(0.1, abs=1e-9) for a, b in itertools.pairwise(kept))


def test_jittered_stamps_still_give_the_rate():
    """Camera stamps jitter by a few ms: frames a little early are still taken (no halving)."""
    stamps = [k / 30 + (0.004 if k % 2 else -0.004) for k in range(300)]
    kept = admitted(FrameRateCap(10.0), stamps)
    assert 95 <= len(kept) <= 101


def test_no_cap_admits_every_frame_and_a_stamp_going_back_starts_over():
    assert admitted(FrameRateCap(0.0), [0.0, 0.001, 0.002]) == [0.0, 0.001, 0.002]
    cap = FrameRateCap(5.0)
    assert admitted(cap, [100.0, 100.1, 100.25]) == [100.0, 100.25]
    assert cap.admit(3.0)  # the simulator restarted: its clock went back


@pytest.mark.parametrize("bad", [-1.0, float("nan"), float("inf")])
def test_a_bad_rate_is_refused_naming_the_key(bad):
    with pytest.raises(ValueError, match="max_rate_hz"):
        FrameRateCap(bad)
    with pytest.raises(ValueError, match="max_rate_hz"):
        Config(max_rate_hz=bad)
