"""The one decode path of every subscriber (Node, FakeNode, DroneWrapper), on an injected clock."""

from __future__ import annotations

import logging

from dronewrapper.msgs import codec
from dronewrapper.msgs.mavros import State
from dronewrapper.runtime.caller import commander_attachment, current_commander, current_sent_at
from dronewrapper.runtime.clock import VirtualClock
from dronewrapper.runtime.delivery import SampleErrors, decoding

KEY = "drone/mavros/state"


def test_a_sample_is_decoded_with_its_commander_recorded():
    got: list[tuple[State, str]] = []
    errors = SampleErrors(logging.getLogger("test"))
    deliver = decoding(State, lambda msg: got.append((msg, current_commander())), errors)
    deliver(KEY, codec.encode(State(mode="OFFBOARD")), commander_attachment("alice"))
    deliver(KEY, codec.encode(State(mode="POSCTL")), None)
    assert [(m.mode, who) for m, who in got] == [("OFFBOARD", "alice"), ("POSCTL", "")]
    assert current_commander() == ""  # only while the callback runs
    assert not errors.decode and not errors.callback


def test_failures_are_counted_per_key_and_logged_at_most_once_a_period(caplog):
    clock = VirtualClock(monotonic=0.0)
    errors = SampleErrors(logging.getLogger("test"), clock=clock, period=5.0)

    def fail(msg: State) -> None:
        raise RuntimeError("boom")

    deliver = decoding(State, fail, errors)
    with caplog.at_level(logging.WARNING, logger="test"):
        for _ in range(3):
            deliver(KEY, b"\xc1", None)  # not msgpack
            deliver(KEY, codec.encode(State()), None)
        clock.advance_to(5.0)
        deliver(KEY, b"\xc1", None)
    assert errors.decode[KEY] == 4 and errors.callback[KEY] == 3
    lines = [r.getMessage() for r in caplog.records]
    assert sum("undecodable sample" in line for line in lines) == 2  # t = 0 and t = 5
    assert sum("callback error" in line and "boom" in line for line in lines) == 1


def test_a_sample_without_attachment_inside_a_handled_one_has_no_commander():
    """The no-op path for samples without attachment must still hide an outer commander."""
    seen: list[tuple[str, object]] = []
    errors = SampleErrors(logging.getLogger("test"))
    inner = decoding(
        State, lambda _m: seen.append((current_commander(), current_sent_at())), errors
    )

    def outer_callback(_msg: State) -> None:
        inner(KEY, codec.encode(State()), None)
        seen.append((current_commander(), current_sent_at()))

    outer = decoding(State, outer_callback, errors)
    outer(KEY, codec.encode(State()), commander_attachment("alice", sent=12.5))
    assert seen == [("", None), ("alice", 12.5)]
    assert (current_commander(), current_sent_at()) == ("", None)
