"""The fidelity bench's step-response figures on traces of known shape."""

from __future__ import annotations

import math

import pytest

from bench.fidelity_metrics import ratio, step_figures, within


def first_order(tau: float, dead: float, n: int = 2001, dt: float = 0.005):
    t = [i * dt for i in range(n)]
    y = [0.0 if ti < dead else 1.0 - math.exp(-(ti - dead) / tau) for ti in t]
    return t, y


def test_first_order_with_dead_time():
    t, y = first_order(tau=0.5, dead=0.2)
    f = step_figures(t, y, 0.0, 0.0, 1.0)
    assert f.delay_s == pytest.approx(0.2 + 0.5 * math.log(1 / 0.9), abs=0.01)
    assert f.rise_s == pytest.approx(0.5 * math.log(9), abs=0.01)  # 2.2 tau
    assert f.overshoot_pct == 0.0
    assert f.settling_s == pytest.approx(0.2 + 0.5 * math.log(10), abs=0.01)  # within 10 %
    assert f.steady_error_pct == pytest.approx(0.0, abs=0.1)


def test_overshoot_and_steady_error_of_a_step_down():
    t = [i * 0.01 for i in range(600)]
    # from 2 to 1: dips to 0.8 (20 % overshoot), settles at 1.1 (10 % short)
    y = [2.0 - min(ti, 1.0) * 1.2 if ti < 1.0 else 0.8 + min(ti - 1.0, 1.0) * 0.3 for ti in t]
    f = step_figures(t, y, 0.0, 2.0, 1.0, band=0.15)
    assert f.overshoot_pct == pytest.approx(20.0, abs=0.5)
    assert f.steady_error_pct == pytest.approx(10.0, abs=0.5)
    assert f.settling_s == pytest.approx(1.0 + 0.05 / 0.3, abs=0.03)


def test_a_response_that_never_arrives_is_nan():
    t = [i * 0.1 for i in range(50)]
    f = step_figures(t, [0.05] * 50, 0.0, 0.0, 1.0)
    assert math.isnan(f.delay_s) and math.isnan(f.rise_s)
    with pytest.raises(ValueError):
        step_figures(t, [0.0] * 50, 0.0, 1.0, 1.0)


def test_ratio_and_band():
    assert ratio(1.0, 0.8) == pytest.approx(1.25) and within(1.25) and not within(1.26)
    assert math.isnan(ratio(1.0, 0.0)) and not within(math.nan)
