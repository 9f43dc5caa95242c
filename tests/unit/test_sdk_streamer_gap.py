"""The setpoint stream across a link gap: nothing is published while the bridge is
unreachable, and a command older than the expiry is never resent when it returns."""

from __future__ import annotations

import logging
import time

import pytest

from dronewrapper.setpoints import velocity_target
from dronewrapper.streamer import SetpointStreamer


def streamer(sent: list) -> SetpointStreamer:
    return SetpointStreamer(sent.append, rate_hz=50.0, expiry=0.5)


def test_nothing_is_published_while_the_link_is_down():
    sent: list = []
    s = streamer(sent)
    try:
        s.link_down()
        s.set(velocity_target(1.0, 0, 0, 0, stamp=1.0))
        time.sleep(0.1)
        assert sent == [] and s.withheld >= 1
    finally:
        s.close()


def test_a_stale_command_is_dropped_when_the_link_returns():
    sent: list = []
    s = streamer(sent)
    try:
        s.set(velocity_target(1.0, 0, 0, 0, stamp=1.0))
        s.link_down()
        s.link_up(now=time.monotonic() + 0.6)  # back 0.6 s after the command: stale
        assert s.target is None and s.dropped_after_gap == 1
        count = len(sent)
        time.sleep(0.1)
        assert len(sent) == count  # the stream stopped
        s.set(velocity_target(0.2, 0, 0, 0, stamp=2.0))  # a new command goes out at once
        assert sent[-1].velocity.x == 0.2
    finally:
        s.close()


def test_the_link_reads_up_only_after_the_stale_command_is_dropped():
    """Readers poll ``link_ok`` without the lock: the moment it reads True, the stale command
    is already gone (observed from inside link_up, where the drop is logged)."""
    s = streamer([])
    seen: list[tuple[bool, int]] = []

    class Observe(logging.Handler):
        def emit(self, record: logging.LogRecord) -> None:
            if "back" in record.getMessage():  # link_up's warning
                seen.append((s.link_ok, s.dropped_after_gap))

    handler = Observe()
    logger = logging.getLogger("dronewrapper.streamer")
    logger.addHandler(handler)
    try:
        s.set(velocity_target(1.0, 0, 0, 0, stamp=1.0))
        s.link_down()
        s.link_up(now=time.monotonic() + 0.6)
        assert seen and not any(up for up, _ in seen), seen  # still down while deciding
        assert s.link_ok and s.dropped_after_gap == 1
    finally:
        logger.removeHandler(handler)
        s.close()


def test_a_fresh_command_resumes_after_a_short_gap():
    sent: list = []
    s = streamer(sent)
    try:
        s.set(velocity_target(1.0, 0, 0, 0, stamp=1.0))
        s.link_down()
        s.link_up()  # well within 0.5 s
        assert s.target is not None and s.dropped_after_gap == 0
        count = len(sent)
        deadline = time.monotonic() + 5
        while len(sent) <= count and time.monotonic() < deadline:
            time.sleep(0.01)
        assert len(sent) > count
    finally:
        s.close()


def test_expiry_must_be_positive():
    with pytest.raises(ValueError, match="expiry"):
        SetpointStreamer(lambda t: None, expiry=0.0)
