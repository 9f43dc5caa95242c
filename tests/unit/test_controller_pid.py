"""PID with real time steps, anti-windup, filtered derivative, output limits and reset."""

from __future__ import annotations

import math

import pytest

from dronewrapper_controller.pid import Pid, PidGains


def test_proportional_only_is_kp_times_error():
    pid = Pid(PidGains(kp=0.5, out_limit=10))
    assert pid.update(2.0, 0.0) == pytest.approx(1.0)
    assert pid.update(-4.0, 0.1) == pytest.approx(-2.0)


def test_output_is_saturated_both_ways():
    pid = Pid(PidGains(kp=1.0, out_limit=0.7))
    assert pid.update(100.0, 0.0) == pytest.approx(0.7)
    assert pid.update(-100.0, 0.1) == pytest.approx(-0.7)


def test_integral_uses_the_real_time_step():
    """Same errors, twice the time between samples -> twice the integral (original: no dt)."""
    fast, slow = Pid(PidGains(ki=1.0, out_limit=100)), Pid(PidGains(ki=1.0, out_limit=100))
    for k in range(11):
        fast.update(1.0, k * 0.05)
        slow.update(1.0, k * 0.10)
    assert fast.integral == pytest.approx(0.5)
    assert slow.integral == pytest.approx(1.0)


def test_derivative_scales_with_one_over_dt():
    """A ramp of 1 unit per sample: D = kd * slope in units per second, not per sample."""

    def d_after_ramp(dt: float) -> float:
        pid = Pid(PidGains(kd=1.0, d_tau=0.0, out_limit=1000))
        for k in range(5):
            pid.update(float(k), k * dt)
        return pid.d

    assert d_after_ramp(0.1) == pytest.approx(10.0)
    assert d_after_ramp(0.02) == pytest.approx(50.0)


def test_first_update_has_no_derivative_kick():
    pid = Pid(PidGains(kp=0.0, kd=5.0, out_limit=100))
    assert pid.update(40.0, 10.0) == 0.0


def test_derivative_is_low_pass_filtered():
    """A one-sample spike moves a filtered D far less than an unfiltered one."""
    raw = Pid(PidGains(kd=1.0, d_tau=0.0, out_limit=1e9))
    filt = Pid(PidGains(kd=1.0, d_tau=0.2, out_limit=1e9))
    for pid in (raw, filt):
        pid.update(0.0, 0.0)
        pid.update(0.0, 0.05)
        pid.update(10.0, 0.10)
    assert raw.d == pytest.approx(200.0)
    assert 0 < filt.d < raw.d / 3


def test_filtered_derivative_converges_to_the_slope():
    pid = Pid(PidGains(kd=1.0, d_tau=0.1, out_limit=1e9))
    for k in range(200):
        pid.update(2.0 * k * 0.02, k * 0.02)  # slope 2 /s
    assert pid.d == pytest.approx(2.0, rel=1e-3)


def test_anti_windup_integrator_does_not_grow_while_saturated():
    """Held far from the setpoint, then released: the output follows the error at once."""
    pid = Pid(PidGains(kp=0.1, ki=1.0, out_limit=1.0))
    t = 0.0
    for _ in range(500):  # 25 s of a large error, output pinned at the limit
        pid.update(5.0, t)
        t += 0.05
    assert pid.output == pytest.approx(1.0)
    assert pid.integral < 1.0 / 1.0 + 1e-9  # stopped at what the limit needs
    out = pid.update(-5.0, t)  # error reverses: no long unwinding
    assert out < 0.6


def test_integrator_clamp():
    pid = Pid(PidGains(ki=0.01, i_limit=2.0, out_limit=100))
    for k in range(100):
        pid.update(1.0, k * 0.1)
    assert pid.integral == pytest.approx(2.0)
    assert pid.i == pytest.approx(0.02)


def test_repeated_stamp_changes_nothing():
    pid = Pid(PidGains(kp=1.0, ki=1.0, out_limit=100))
    pid.update(1.0, 0.0)
    first = pid.update(1.0, 0.1)
    integral = pid.integral
    assert pid.update(50.0, 0.1) == first  # same frame stamp again
    assert pid.update(50.0, 0.05) == first  # a stamp from the past
    assert pid.integral == integral


def test_long_gap_restarts_integral_and_derivative():
    pid = Pid(PidGains(kp=0.0, ki=1.0, kd=1.0, out_limit=100, max_dt=0.5))
    for k in range(10):
        pid.update(1.0, k * 0.1)
    assert pid.integral > 0.5
    out = pid.update(3.0, 100.0)  # a 99 s gap: no huge integral, no derivative jump
    assert pid.integral == 0.0 and out == 0.0


def test_reset_forgets_everything():
    pid = Pid(PidGains(kp=1.0, ki=1.0, kd=1.0, out_limit=100))
    for k in range(10):
        pid.update(float(k), k * 0.1)
    pid.reset()
    assert (pid.integral, pid.output, pid.d) == (0.0, 0.0, 0.0)
    assert pid.update(2.0, 50.0) == pytest.approx(2.0)


def test_non_finite_input_is_refused_and_changes_nothing():
    pid = Pid(PidGains(kp=1.0, out_limit=10))
    pid.update(1.0, 0.0)
    for bad in (math.nan, math.inf):
        with pytest.raises(ValueError):
            pid.update(bad, 0.1)
    assert pid.output == pytest.approx(1.0)


@pytest.mark.parametrize(
    "kwargs",
    [{"out_limit": 0}, {"out_limit": -1}, {"i_limit": -1}, {"d_tau": -0.1}, {"kp": math.nan}],
)
def test_bad_gains_are_refused(kwargs):
    with pytest.raises(ValueError):
        PidGains(**kwargs)


def test_closed_loop_first_order_plant_converges_without_overshoot_blowup():
    """PI on x' = u (a velocity-commanded axis) reaches the setpoint with bounded overshoot."""
    pid = Pid(PidGains(kp=1.0, ki=0.2, kd=0.05, out_limit=1.0, i_limit=5.0))
    x, t, dt = 0.0, 0.0, 0.05
    peak = 0.0
    for _ in range(600):
        u = pid.update(5.0 - x, t)
        x += u * dt
        t += dt
        peak = max(peak, x)
    assert x == pytest.approx(5.0, abs=0.05)
    assert peak < 6.0
