"""The setpoint stream: one thread, >= 20 Hz, until changed or stopped; the optional deadman."""

from __future__ import annotations

import threading
import time

import pytest

from dronewrapper.msgs.mavros import PositionTarget
from dronewrapper.setpoints import velocity_target
from dronewrapper.streamer import SetpointStreamer
from support import wait_for


class Recorder:
    def __init__(self) -> None:
        self.sent: list[tuple[float, PositionTarget, int]] = []
        self.threads: set[str] = set()
        self.lock = threading.Lock()

    def __call__(self, msg: PositionTarget) -> None:
        with self.lock:
            self.sent.append((time.monotonic(), msg, msg.header.seq))
            self.threads.add(threading.current_thread().name)


def test_set_publishes_at_once_then_repeats_at_rate():
    rec = Recorder()
    stream = SetpointStreamer(rec, rate_hz=30.0, name="stream-under-test")
    try:
        target = velocity_target(0, 0, 0, 1.0, stamp=42.0)
        stream.set(target)
        assert len(rec.sent) == 1  # published on the caller's thread, before set() returns
        time.sleep(1.0)
        count = len(rec.sent)
        # 30 Hz nominal; >= 20 Hz required, allow a loaded CI machine some slack
        assert count >= 20, count
        assert all(msg.yaw_rate == 1.0 and msg.header.stamp == 42.0 for _, msg, _ in rec.sent)
        assert [seq for *_, seq in rec.sent] == list(range(len(rec.sent)))
        assert rec.threads <= {"stream-under-test", threading.current_thread().name}
    finally:
        stream.close()


def test_changed_setpoint_replaces_the_old_one():
    rec = Recorder()
    stream = SetpointStreamer(rec, rate_hz=50.0)
    try:
        stream.set(velocity_target(1, 0, 0, 0, stamp=1.0))
        time.sleep(0.2)
        stream.set(velocity_target(0, 0, 0, -1, stamp=2.0))
        mark = len(rec.sent)
        time.sleep(0.3)
        later = [msg for _, msg, _ in rec.sent[mark:]]
        assert later and all(msg.yaw_rate == -1 and msg.velocity.x == 0 for msg in later)
    finally:
        stream.close()


def test_stop_stops_publishing_and_a_new_set_resumes():
    rec = Recorder()
    stream = SetpointStreamer(rec, rate_hz=50.0)
    try:
        stream.set(velocity_target(1, 0, 0, 0, stamp=1.0))
        time.sleep(0.2)
        stream.stop()
        assert not stream.active
        time.sleep(0.05)
        mark = len(rec.sent)
        time.sleep(0.4)
        assert len(rec.sent) == mark
        stream.set(velocity_target(0, 1, 0, 0, stamp=1.0))
        wait_for(lambda: len(rec.sent) >= mark + 5, 5.0, what="stream resumed")
    finally:
        stream.close()


def test_idle_timeout_is_a_deadman():
    rec = Recorder()
    stream = SetpointStreamer(rec, rate_hz=50.0, idle_timeout=0.3)
    try:
        stream.set(velocity_target(1, 0, 0, 0, stamp=1.0))
        wait_for(lambda: not stream.active, 5.0, what="deadman")
        mark = len(rec.sent)
        time.sleep(0.3)
        assert len(rec.sent) == mark
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
        wait_for(lambda: stream.published >= 3 and stream.errors >= 3, 5.0, what="retries")
    finally:
        stream.close()


def test_rate_below_20_hz_is_refused_and_closed_stream_refuses_sets():
    with pytest.raises(ValueError, match="20"):
        SetpointStreamer(lambda m: None, rate_hz=10.0)
    stream = SetpointStreamer(lambda m: None)
    stream.close()
    with pytest.raises(RuntimeError, match="closed"):
        stream.set(velocity_target(0, 0, 0, 0, stamp=1.0))
