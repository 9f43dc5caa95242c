"""The SDK's setpoint stream: one thread, >= 20 Hz, until changed or stopped; the optional
deadman. In virtual time: every period and stamp below is exact."""

from __future__ import annotations

import threading
from collections.abc import Iterator

import pytest

from dronewrapper.client.stream import SetpointStreamer
from dronewrapper.msgs.mavros import PositionTarget
from dronewrapper.runtime.clock import VirtualClock
from dronewrapper.setpoints import velocity_target


class Recorder:
    """Every publication: (clock time, message, seq, thread name)."""

    def __init__(self, clock: VirtualClock) -> None:
        self.clock = clock
        self.sent: list[tuple[float, PositionTarget, int, str]] = []

    def __call__(self, msg: PositionTarget) -> None:
        name = threading.current_thread().name
        self.sent.append((self.clock(), msg, msg.header.seq, name))

    def times(self, since: int = 0) -> list[float]:
        return [round(t - 1000.0, 9) for t, *_ in self.sent[since:]]


@pytest.fixture
def clock() -> VirtualClock:
    return VirtualClock(monotonic=1000.0)


@pytest.fixture
def streamed(clock) -> Iterator[tuple[Recorder, SetpointStreamer]]:
    """A 50 Hz streamer publishing to a recorder (closed after the test)."""
    rec = Recorder(clock)
    stream = SetpointStreamer(rec, clock=clock, rate_hz=50.0)
    yield rec, stream
    stream.close()


def test_set_publishes_at_once_then_repeats_at_rate(clock):
    rec = Recorder(clock)
    stream = SetpointStreamer(rec, clock=clock, rate_hz=50.0, name="stream-under-test")
    try:
        stream.set(velocity_target(0, 0, 0, 1.0, stamp=42.0))
        assert rec.sent[0][3] == threading.current_thread().name  # out on the caller's thread
        clock.run_for(0.1)
        assert rec.times() == pytest.approx([0.0, 0.02, 0.04, 0.06, 0.08, 0.1])
        assert all(msg.yaw_rate == 1.0 and msg.header.stamp == 42.0 for _, msg, *_ in rec.sent)
        assert [seq for _, _, seq, _ in rec.sent] == list(range(6))
        assert {name for *_, name in rec.sent[1:]} == {"stream-under-test"}
    finally:
        stream.close()


def test_changed_setpoint_replaces_the_old_one_and_restarts_the_period(clock, streamed):
    rec, stream = streamed
    stream.set(velocity_target(1, 0, 0, 0, stamp=1.0))
    clock.run_for(0.05)
    stream.set(velocity_target(0, 0, 0, -1, stamp=2.0))
    mark = len(rec.sent)
    clock.run_for(0.1)
    assert rec.times(mark - 1) == pytest.approx([0.05, 0.07, 0.09, 0.11, 0.13, 0.15])
    assert all(msg.yaw_rate == -1 for _, msg, *_ in rec.sent[mark - 1 :])


def test_stop_stops_publishing_and_a_new_set_resumes(clock, streamed):
    rec, stream = streamed
    stream.set(velocity_target(1, 0, 0, 0, stamp=1.0))
    clock.run_for(0.05)
    stream.stop()
    assert not stream.active
    mark = len(rec.sent)
    clock.run_for(0.4)  # 20 periods
    assert len(rec.sent) == mark
    stream.set(velocity_target(0, 1, 0, 0, stamp=1.0))
    clock.run_for(0.1)
    assert len(rec.sent) == mark + 6


def test_idle_timeout_is_a_deadman(clock):
    rec = Recorder(clock)
    stream = SetpointStreamer(rec, clock=clock, rate_hz=50.0, idle_timeout=0.3)
    try:
        stream.set(velocity_target(1, 0, 0, 0, stamp=1.0))
        clock.run_for(1.0)
        assert not stream.active
        assert rec.times()[-1] == pytest.approx(0.3)  # the last repetition within 0.3 s
    finally:
        stream.close()


def test_publish_errors_are_counted_not_fatal(clock):
    calls = []

    def flaky(msg: PositionTarget) -> None:
        calls.append(msg)
        if len(calls) % 2:
            raise RuntimeError("transport hiccup")

    stream = SetpointStreamer(flaky, clock=clock, rate_hz=50.0)
    try:
        stream.set(velocity_target(0, 0, 0, 0, stamp=1.0))
        clock.run_for(0.1)
        assert stream.published == 3 and stream.core.errors == 3
    finally:
        stream.close()


def test_rate_below_20_hz_is_refused_and_closed_stream_refuses_sets():
    with pytest.raises(ValueError, match="20"):
        SetpointStreamer(lambda m: None, rate_hz=10.0)
    stream = SetpointStreamer(lambda m: None)
    stream.close()
    with pytest.raises(RuntimeError, match="closed"):
        stream.set(velocity_target(0, 0, 0, 0, stamp=1.0))
