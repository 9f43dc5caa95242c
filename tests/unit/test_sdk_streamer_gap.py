"""The setpoint stream across a link gap (runtime.setpoint_stream, the one core of the SDK's
and the services' streams): nothing is published while the bridge is unreachable, and a
command older than the expiry is never resent when it returns."""

from __future__ import annotations

import logging

import pytest

from dronewrapper.client.setpoint_stream import SetpointStream
from dronewrapper.setpoints import velocity_target


def stream(sent: list) -> SetpointStream:
    s = SetpointStream(sent.append, rate_hz=50.0, expiry=0.5)
    s.link(True, 0.0)  # the bridge's subscriber reachable once
    return s


def run(s: SetpointStream, start: float, end: float) -> None:
    """Drive the stream as its thread or loop does, from ``start`` to ``end`` (s)."""
    now = start
    while (due := s.next_due()) <= end:
        now = max(now, due)
        s.poll(now)


def test_nothing_is_published_while_the_link_is_down():
    sent: list = []
    s = stream(sent)
    s.link(False, 1.0)
    s.set(velocity_target(1.0, 0, 0, 0, stamp=1.0), 1.0)
    run(s, 1.0, 1.1)
    assert sent == [] and s.withheld == 6


def test_unreachable_counts_only_once_the_bridge_was_reachable():
    sent: list = []
    s = SetpointStream(sent.append, rate_hz=50.0)
    s.link(False, 0.0)  # no bridge yet: not a gap
    s.set(velocity_target(1.0, 0, 0, 0, stamp=1.0), 0.0)
    assert s.link_ok and len(sent) == 1


def test_a_stale_command_is_dropped_when_the_link_returns():
    sent: list = []
    s = stream(sent)
    s.set(velocity_target(1.0, 0, 0, 0, stamp=1.0), 10.0)
    s.link(False, 10.1)
    s.link(True, 10.6)  # back 0.6 s after the command: stale
    assert s.target is None and s.dropped_after_gap == 1 and s.next_due() == float("inf")
    count = len(sent)
    run(s, 10.6, 11.0)
    assert len(sent) == count  # the stream stopped
    s.set(velocity_target(0.2, 0, 0, 0, stamp=2.0), 11.0)  # a new command goes out at once
    assert sent[-1].velocity.x == 0.2


def test_the_link_reads_up_only_after_the_stale_command_is_dropped():
    """Readers poll ``link_ok`` without a lock: the moment it reads True, the stale command is
    already gone (observed from inside link_up, where the drop is logged)."""
    s = stream([])
    seen: list[tuple[bool, int]] = []

    class Observe(logging.Handler):
        def emit(self, record: logging.LogRecord) -> None:
            if "back" in record.getMessage():  # link_up's warning
                seen.append((s.link_ok, s.dropped_after_gap))

    handler = Observe()
    logger = logging.getLogger("dronewrapper.setpoints")
    logger.addHandler(handler)
    try:
        s.set(velocity_target(1.0, 0, 0, 0, stamp=1.0), 0.0)
        s.link(False, 0.1)
        s.link(True, 0.6)
        assert seen and not any(up for up, _ in seen), seen  # still down while deciding
        assert s.link_ok and s.dropped_after_gap == 1
    finally:
        logger.removeHandler(handler)


def test_a_fresh_command_resumes_after_a_short_gap():
    sent: list = []
    s = stream(sent)
    s.set(velocity_target(1.0, 0, 0, 0, stamp=1.0), 0.0)
    s.link(False, 0.1)
    s.link(True, 0.3)  # well within 0.5 s
    assert s.target is not None and s.dropped_after_gap == 0
    count = len(sent)
    run(s, 0.3, 0.4)
    assert len(sent) > count


def test_expiry_must_be_positive():
    with pytest.raises(ValueError, match="expiry"):
        SetpointStream(lambda t: None, expiry=0.0)
