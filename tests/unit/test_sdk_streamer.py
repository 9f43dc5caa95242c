"""The setpoint stream: one thread, >= 20 Hz, until changed or stopped; the optional deadman."""

from __future__ import annotations

import itertools
import threading
import time

import pytest

from dronewrapper.msgs.mavros import PositionTarget
from dronewrapper.setpoints import velocity_target
from dronewrapper.streamer import SetpointStreamer
from support import wait_for


class Recorder:
    def __init__(self) -> None:
        self.sent: list[tuple[float, PositionTarget, int, str]] = []
        self.lock = threading.Lock()

    def __call__(self, msg: PositionTarget) -> None:
        with self.lock:
            name = threading.current_thread().name
            self.sent.append((time.monotonic(), msg, msg.header.seq, name))

    def count(self) -> int:
        with self.lock:
            return len(self.sent)

    def since(self, index: int) -> list[PositionTarget]:
        with self.lock:
            return [msg for _, msg, *_ in self.sent[index:]]


def test_set_publishes_at_once_then_repeats_at_rate():
    rec = Recorder()
    stream = SetpointStreamer(rec, rate_hz=30.0, name="stream-under-test")
    try:
        target = velocity_target(0, 0, 0, 1.0, stamp=42.0)
        before = time.monotonic()
        stream.set(target)
        returned = time.monotonic()
        # the first one went out on the caller's thread, before set() returned
        first_at, _, first_seq, first_thread = rec.sent[0]
        assert before <= first_at <= returned and first_seq == 0
        assert first_thread == threading.current_thread().name
        wait_for(lambda: rec.count() >= 31, 10.0, what="30 repetitions")
        with rec.lock:
            sent = list(rec.sent)
        # 30 Hz nominal, >= 20 Hz required: the median gap is robust to a few scheduler stalls
        gaps = sorted(b[0] - a[0] for a, b in itertools.pairwise(sent))
        median = gaps[len(gaps) // 2]
        assert median <= 1.0 / 20.0, f"median gap {median * 1000:.0f} ms"
        assert all(msg.yaw_rate == 1.0 and msg.header.stamp == 42.0 for _, msg, *_ in sent)
        assert [seq for _, _, seq, _ in sent] == list(range(len(sent)))
        assert {name for *_, name in sent[1:]} == {"stream-under-test"}
    finally:
        stream.close()


def test_changed_setpoint_replaces_the_old_one():
    rec = Recorder()
    stream = SetpointStreamer(rec, rate_hz=50.0)
    try:
        stream.set(velocity_target(1, 0, 0, 0, stamp=1.0))
        wait_for(lambda: rec.count() >= 3, 10.0, what="the first setpoint repeated")
        stream.set(velocity_target(0, 0, 0, -1, stamp=2.0))
        mark = rec.count()  # set() published under the stream's lock: all later ones are new
        wait_for(lambda: rec.count() >= mark + 5, 10.0, what="the new setpoint repeated")
        later = rec.since(mark)
        assert all(msg.yaw_rate == -1 and msg.velocity.x == 0 for msg in later)
    finally:
        stream.close()


def test_stop_stops_publishing_and_a_new_set_resumes():
    rec = Recorder()
    stream = SetpointStreamer(rec, rate_hz=50.0)
    try:
        stream.set(velocity_target(1, 0, 0, 0, stamp=1.0))
        wait_for(lambda: rec.count() >= 3, 10.0, what="streaming")
        stream.stop()
        assert not stream.active
        mark = rec.count()  # stop() took the stream's lock: nothing is half-published
        time.sleep(0.4)  # 20 periods
        assert rec.count() == mark
        stream.set(velocity_target(0, 1, 0, 0, stamp=1.0))
        wait_for(lambda: rec.count() >= mark + 5, 10.0, what="stream resumed")
    finally:
        stream.close()


def test_idle_timeout_is_a_deadman():
    rec = Recorder()
    stream = SetpointStreamer(rec, rate_hz=50.0, idle_timeout=0.3)
    try:
        stream.set(velocity_target(1, 0, 0, 0, stamp=1.0))
        wait_for(lambda: not stream.active, 10.0, what="deadman")
        mark = rec.count()
        time.sleep(0.3)
        assert rec.count() == mark
        # the last repetition went out within the 0.3 s deadman (3x margin for a busy machine)
        assert rec.sent[-1][0] - rec.sent[0][0] < 1.0
    finally:
        stream.close()


def test_publish_errors_are_counted_not_fatal():
    calls = []

    def flaky(msg: PositionTarget) -> None:
        calls.append(msg)
        if len(calls) % 2:
            raise RuntimeError("transport hiccup")

    stream = SetpointStreamer(flaky, rate_hz=50.0)
    try:
        stream.set(velocity_target(0, 0, 0, 0, stamp=1.0))
        wait_for(lambda: stream.published >= 3 and stream.errors >= 3, 10.0, what="retries")
    finally:
        stream.close()


def test_rate_below_20_hz_is_refused_and_closed_stream_refuses_sets():
    with pytest.raises(ValueError, match="20"):
        SetpointStreamer(lambda m: None, rate_hz=10.0)
    stream = SetpointStreamer(lambda m: None)
    stream.close()
    with pytest.raises(RuntimeError, match="closed"):
        stream.set(velocity_target(0, 0, 0, 0, stamp=1.0))
