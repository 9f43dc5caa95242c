"""Latest-value inputs and the rate keeper, on a virtual clock (no real waits)."""

from __future__ import annotations

import math
import threading

import pytest

from dronewrapper.runtime import Latest, Ratekeeper
from dronewrapper.runtime.clock import VirtualClock


def test_latest_reports_age_and_freshness():
    clock = VirtualClock(monotonic=100.0)
    latest: Latest[int] = Latest("pose", clock=clock)
    assert latest.value is None and math.isinf(latest.age()) and latest.fresh(10) is None
    latest.update(1)
    clock.advance_to(100.3)
    assert latest.age() == pytest.approx(0.3)
    assert latest.fresh(0.5) == 1
    clock.advance_to(100.6)
    assert latest.fresh(0.5) is None, "a stale value must never come back as fresh"
    assert latest.value == 1 and latest.count == 1


def test_latest_wait_times_out_with_the_input_named_in_clock_time():
    clock = VirtualClock(monotonic=0.0)
    latest: Latest[int] = Latest("drone/mavros/state", clock=clock)
    with pytest.raises(TimeoutError, match="drone/mavros/state"):
        latest.wait(5.0)
    assert clock() == 5.0, "waited the whole timeout, in the clock's time"


def test_latest_wait_for_a_newer_value_from_a_worker():
    clock = VirtualClock(monotonic=0.0)
    latest: Latest[int] = Latest(clock=clock)
    latest.update(1)
    count = latest.count
    producer = clock.thread(lambda: (clock.sleep(0.25), latest.update(2)), "producer")
    producer.start()
    assert latest.wait(10.0, newer_than=count) == 2
    assert clock() == 0.25, "woke when the value came, not at the timeout"


def test_ratekeeper_keeps_rate_and_stops_promptly():
    clock = VirtualClock(monotonic=0.0)
    stop = threading.Event()
    ticks: list[float] = []

    def loop() -> None:
        rate = Ratekeeper(100, stop=stop, clock=clock)
        while rate.sleep() and len(ticks) < 20:
            ticks.append(clock())
        slow = Ratekeeper(0.1, stop=stop, clock=clock)  # a 10 s period must not delay the stop
        ticks.append(-1.0 if slow.sleep() else clock())

    worker = clock.thread(loop, "loop")
    worker.start()
    clock.run_until(lambda: len(ticks) == 20, 5.0, "20 ticks")
    assert ticks == pytest.approx([0.01 * (i + 1) for i in range(20)])
    stopper = clock.thread(lambda: (clock.sleep(0.05), stop.set()), "stopper")
    stopper.start()
    clock.run_until(lambda: worker.finished, 5.0, "the slow loop stopped")
    assert ticks[-1] == pytest.approx(0.25)  # at the stop, far below the 10 s period


def test_ratekeeper_counts_lag_and_does_not_burst():
    clock = VirtualClock(monotonic=100.0)
    rate = Ratekeeper(10, clock=clock)
    clock.advance_to(105.0)  # a long stall
    assert rate.sleep() is True
    assert rate.lagged == 1
    rate.sleep()
    assert rate.lagged == 1, "after a stall the schedule restarts instead of bursting"
    assert clock() == pytest.approx(105.1)


def test_ratekeeper_rejects_bad_rates():
    with pytest.raises(ValueError):
        Ratekeeper(0)


def test_take_returns_newest_with_its_number():
    """The newest-frame policy (perception): only the newest is taken, skipped ones countable."""
    slot: Latest[str] = Latest(clock=VirtualClock())
    assert slot.take(0.01, newer_than=0) is None
    for name in ("a", "b", "c"):
        slot.update(name)
    assert slot.take(0.01, newer_than=0) == (3, "c")  # a and b were dropped
    assert slot.take(0.01, newer_than=3) is None  # nothing newer
    slot.update("d")
    assert slot.take(0.01, newer_than=3) == (4, "d")


def test_take_wakes_when_a_value_arrives():
    clock = VirtualClock(monotonic=0.0)
    slot: Latest[int] = Latest(clock=clock)
    clock.thread(lambda: (clock.sleep(0.05), slot.update(7)), "producer").start()
    assert slot.take(10.0, newer_than=0) == (1, 7)
    assert clock() == 0.05
