"""The injectable clock (dronewrapper.runtime.clock): virtual time for threaded services."""

from __future__ import annotations

import threading

import pytest

from dronewrapper.runtime.clock import REAL, VirtualClock


def test_the_real_clock_is_the_system_one():
    import time

    assert abs(REAL.time() - time.time()) < 1.0
    assert REAL() == pytest.approx(time.monotonic(), abs=1.0)
    stop = threading.Event()
    stop.set()
    assert REAL.wait(stop, 5.0)  # set: returns at once


def test_time_jumps_to_each_wait_in_deadline_order():
    clock = VirtualClock(monotonic=10.0, time=1000.0)
    woke: list[tuple[str, float, float]] = []

    def sleeper(name: str, periods: list[float]) -> None:
        for period in periods:
            clock.sleep(period)
            woke.append((name, clock.monotonic(), clock.time()))

    a = clock.thread(lambda: sleeper("a", [0.3, 0.3, 0.3]), "a")
    b = clock.thread(lambda: sleeper("b", [0.5, 0.5]), "b")
    a.start()
    b.start()
    clock.run_until(lambda: a.finished and b.finished, 5.0, "both sleepers")
    assert [(n, round(t - 10.0, 9)) for n, t, _ in woke] == [
        ("a", 0.3),
        ("b", 0.5),
        ("a", 0.6),
        ("a", 0.9),
        ("b", 1.0),
    ]
    assert all(wall - mono == 990.0 for _, mono, wall in woke)  # both clocks move together


def test_a_wait_ends_at_once_when_its_event_is_set_by_a_worker():
    clock = VirtualClock()
    stop = threading.Event()
    results: list[tuple[bool, float]] = []
    waiter = clock.thread(lambda: results.append((clock.wait(stop, 10.0), clock())), "waiter")
    setter = clock.thread(lambda: (clock.sleep(2.0), stop.set()), "setter")
    waiter.start()
    setter.start()
    clock.run_until(lambda: results, 5.0, "the waiter")
    assert results == [(True, 1002.0)]


def test_wait_for_releases_the_condition_and_times_out_in_virtual_time():
    clock = VirtualClock()
    cond = threading.Condition()
    box: list[int] = []
    outcome: list[tuple[bool, float]] = []

    def consumer() -> None:
        with cond:
            got = clock.wait_for(cond, lambda: bool(box), 1.0)
            outcome.append((got, clock()))
            got = clock.wait_for(cond, lambda: len(box) > 1, 1.0)
            outcome.append((got, clock()))

    def producer() -> None:
        clock.sleep(0.25)
        with cond:  # free while the consumer waits
            box.append(1)
            cond.notify_all()

    for worker in (clock.thread(consumer, "consumer"), clock.thread(producer, "producer")):
        worker.start()
    clock.run_until(lambda: len(outcome) == 2, 5.0, "the consumer")
    assert outcome == [(True, 1000.25), (False, 1001.25)]


def test_a_worker_joins_another_in_virtual_time():
    clock = VirtualClock()
    joined: list[tuple[bool, float]] = []

    def parent() -> None:
        child = clock.thread(lambda: clock.sleep(3.0), "child")
        child.start()
        child.join(1.0)  # gives up after 1 s of virtual time
        joined.append((child.is_alive(), clock()))
        child.join()
        joined.append((child.is_alive(), clock()))

    clock.thread(parent, "parent").start()
    clock.run_until(lambda: len(joined) == 2, 5.0, "the joins")
    assert joined == [(True, 1001.0), (False, 1003.0)]


def test_run_until_says_when_it_cannot_be_done():
    clock = VirtualClock()
    clock.thread(lambda: clock.sleep(10.0), "late").start()
    with pytest.raises(AssertionError, match=r"not within 2 s \(virtual\): something"):
        clock.run_until(lambda: False, 2.0, "something")
    assert clock() == 1002.0
    clock.run_for(9.0)  # the sleeper ends at 1010
    assert clock() == 1011.0
    with pytest.raises(AssertionError, match="nothing left to happen"):
        clock.run_until(lambda: False, 2.0, "more")

    released = threading.Event()

    def wait_without_end() -> None:
        cond = threading.Condition()
        with cond:
            clock.wait_for(cond, released.is_set, None)

    worker = clock.thread(wait_without_end, "forever")
    worker.start()
    with pytest.raises(AssertionError, match="nothing left to happen, never: more"):
        clock.run_until(lambda: False, 2.0, "more")
    released.set()  # by the test, not through the clock: seen all the same
    clock.run_until(lambda: worker.finished, 1.0, "the release")
    assert clock() == 1011.0
