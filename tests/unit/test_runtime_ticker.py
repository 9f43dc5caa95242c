"""The shared ticker (dronewrapper.runtime.ticker): one thread, every caller at its rate, in
virtual time."""

from __future__ import annotations

import threading

import pytest

from dronewrapper.runtime.clock import VirtualClock
from dronewrapper.runtime.ticker import Ticker


def test_every_caller_ticks_at_the_rate_from_one_thread():
    clock = VirtualClock()
    ticker = Ticker(30.0, clock=clock)
    threads: dict[str, set[str]] = {"a": set(), "b": set(), "c": set()}
    counts = dict.fromkeys(threads, 0)
    stop = threading.Event()

    def caller(name: str):
        def tick() -> None:
            counts[name] += 1
            threads[name].add(threading.current_thread().name)

        return tick

    for name in threads:
        ticker.join(caller(name), stop)
    clock.run_for(1.01)  # 30 periods (a hundredth over: no tick on the window's edge)
    assert counts == {"a": 30, "b": 30, "c": 30}
    assert {n for names in threads.values() for n in names} == {"ticker"}  # one thread
    stop.set()


def test_a_caller_leaves_when_its_stop_is_set_and_the_thread_ends_with_the_last():
    clock = VirtualClock()
    ticker = Ticker(20.0, clock=clock)
    first, second = threading.Event(), threading.Event()
    counts = [0, 0]
    ticker.join(lambda: counts.__setitem__(0, counts[0] + 1), first)
    ticker.join(lambda: counts.__setitem__(1, counts[1] + 1), second)
    clock.run_for(0.52)
    first.set()
    clock.run_for(0.5)
    assert counts == [10, 20]
    assert ticker.callers == 1
    second.set()
    clock.run_for(0.2)
    assert ticker.callers == 0
    again = threading.Event()
    ticker.join(lambda: counts.__setitem__(0, counts[0] + 1), again)  # a new thread
    clock.run_for(0.51)
    assert counts[0] == 20
    again.set()


def test_a_failing_tick_is_counted_and_the_others_go_on():
    clock = VirtualClock()
    ticker = Ticker(10.0, clock=clock)
    stop = threading.Event()
    ok = [0]

    def broken() -> None:
        raise RuntimeError("broken tick")

    ticker.join(broken, stop)
    ticker.join(lambda: ok.__setitem__(0, ok[0] + 1), stop)
    clock.run_for(1.05)
    assert ok == [10]
    assert ticker.errors == 10
    stop.set()


def test_rate_must_be_positive():
    with pytest.raises(ValueError, match="rate"):
        Ticker(0.0)
