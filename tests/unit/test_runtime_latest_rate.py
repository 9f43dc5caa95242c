"""Latest-value inputs and the rate keeper, on an injected clock."""

from __future__ import annotations

import math
import threading
import time

import pytest

from dronewrapper.runtime import Latest, Ratekeeper


class FakeClock:
    def __init__(self) -> None:
        self.now = 100.0

    def __call__(self) -> float:
        return self.now


def test_latest_reports_age_and_freshness():
    clock = FakeClock()
    latest: Latest[int] = Latest("pose", clock=clock)
    assert latest.value is None and math.isinf(latest.age()) and latest.fresh(10) is None
    latest.update(1)
    clock.now += 0.3
    assert latest.age() == pytest.approx(0.3)
    assert latest.fresh(0.5) == 1
    clock.now += 0.3
    assert latest.fresh(0.5) is None, "a stale value must never come back as fresh"
    assert latest.value == 1 and latest.count == 1


def test_latest_wait_times_out_with_the_input_named():
    latest: Latest[int] = Latest("drone/mavros/state")
    with pytest.raises(TimeoutError, match="drone/mavros/state"):
        latest.wait(0.05)


def test_latest_wait_for_a_newer_value():
    latest: Latest[int] = Latest()
    latest.update(1)
    count = latest.count
    threading.Timer(0.05, latest.update, args=(2,)).start()
    assert latest.wait(10.0, newer_than=count) == 2


def test_ratekeeper_keeps_rate_and_stops_promptly():
    stop = threading.Event()
    rate = Ratekeeper(100, stop=stop)
    start = time.monotonic()
    ticks = 0
    while rate.sleep() and ticks < 20:
        ticks += 1
    elapsed = time.monotonic() - start
    assert 0.15 < elapsed < 2.0  # 20 ticks at 100 Hz; generous upper bound on a busy machine
    threading.Timer(0.05, stop.set).start()
    slow = Ratekeeper(0.1, stop=stop)  # a 10 s period must not delay the stop
    t0 = time.monotonic()
    assert slow.sleep() is False
    assert time.monotonic() - t0 < 5.0  # far below the 10 s period


def test_ratekeeper_counts_lag_and_does_not_burst():
    clock = FakeClock()
    rate = Ratekeeper(10, clock=clock)
    clock.now += 5.0  # a long stall
    assert rate.sleep() is True
    assert rate.lagged == 1
    clock.now += 0.0
    rate.sleep()
    assert rate.lagged == 1, "after a stall the schedule restarts instead of bursting"


def test_ratekeeper_rejects_bad_rates():
    with pytest.raises(ValueError):
        Ratekeeper(0)


def test_take_returns_newest_with_its_number():
    """The newest-frame policy (perception): only the newest is taken, skipped ones countable."""
    slot: Latest[str] = Latest()
    assert slot.take(0.01, newer_than=0) is None
    for name in ("a", "b", "c"):
        slot.update(name)
    assert slot.take(0.01, newer_than=0) == (3, "c")  # a and b were dropped
    assert slot.take(0.01, newer_than=3) is None  # nothing newer
    slot.update("d")
    assert slot.take(0.01, newer_than=3) == (4, "d")


def test_take_wakes_when_a_value_arrives():
    slot: Latest[int] = Latest()
    threading.Timer(0.05, slot.update, args=(7,)).start()
    assert slot.take(10.0, newer_than=0) == (1, 7)
