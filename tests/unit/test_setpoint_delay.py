"""The late-setpoint rule: offset learning, a burst refused, a slow steady link accepted."""

from __future__ import annotations

import pytest

from dronewrapper.runtime.caller import commander_attachment, commander_of, origin_of
from dronewrapper_bridge_base.setpoint_delay import SetpointDelay

OFFSET = 1234.5  # s: the publisher's clock ahead of ours (unsynchronised clocks)
PERIOD = 1 / 30  # s: the SDK's setpoint stream


def steady(rule: SetpointDelay, start: float, seconds: float, delay: float, who: str = "ada"):
    """Setpoints sent every PERIOD from ``start`` (our clock), each arriving ``delay`` later;
    returns the verdicts."""
    verdicts = []
    n = round(seconds / PERIOD)
    for i in range(n):
        t = start + i * PERIOD
        verdicts.append(rule.judge(who, t + OFFSET, t + delay))
    return verdicts


def test_the_offset_is_learned_without_synchronised_clocks():
    rule = SetpointDelay(0.3)
    assert not any(v.late for v in steady(rule, 0.0, 2.0, 0.01))
    assert rule.min_lag("ada") == pytest.approx(0.01 - OFFSET)
    assert rule.refused == 0


def test_a_burst_held_during_a_cut_is_refused():
    rule = SetpointDelay(0.3)
    steady(rule, 0.0, 2.0, 0.01)
    # a 2 s cut: the setpoints sent during it arrive together when it ends, at t = 4.0
    sent = [2.0 + i * PERIOD for i in range(60)]
    verdicts = [rule.judge("ada", s + OFFSET, 4.0) for s in sent]
    lags = [v.excess for v in verdicts]
    late = [v.late for v in verdicts]
    # all of it: the tail, sent less than 0.3 s before it arrived, was queued behind the rest
    assert all(late)
    assert max(lags) == pytest.approx(2.0 - 0.01, abs=1e-6) and min(lags) < 0.3
    assert rule.refused == len(sent)
    # the stream goes on: fresh setpoints fly again 0.3 s after the burst
    after = steady(rule, 4.0, 1.0, 0.01)
    assert all(v.late for v in after[:9]) and not any(v.late for v in after[10:])


def test_after_a_late_setpoint_only_one_sent_the_threshold_after_its_arrival_flies():
    rule = SetpointDelay(0.3)
    steady(rule, 0.0, 2.0, 0.01)
    assert rule.judge("ada", 2.0 + OFFSET, 2.5).late  # waited 0.49 s more than usual
    assert rule.judge("ada", 2.45 + OFFSET, 2.5).late  # queued behind it (waited 0.04 s)
    assert rule.judge("ada", 2.7 + OFFSET, 2.71).late  # fresh, but too soon after it
    assert not rule.judge("ada", 2.8 + OFFSET, 2.81).late  # 0.3 s after: obeyed


def test_a_long_silence_keeps_the_minimum():
    rule = SetpointDelay(0.3, window_s=10.0)
    steady(rule, 0.0, 1.0, 0.01)
    # a 30 s cut, longer than the window: its burst is still judged against the old lag
    verdicts = [rule.judge("ada", 1.0 + i * PERIOD + OFFSET, 31.0) for i in range(600)]
    assert all(v.late for v in verdicts[:-10])


def test_a_slow_steady_link_is_accepted():
    rule = SetpointDelay(0.3)
    verdicts = steady(rule, 0.0, 5.0, 0.8)  # 0.8 s of delay, every time
    assert not any(v.late for v in verdicts)
    # jitter within the threshold is accepted too
    assert not rule.judge("ada", 5.0 + OFFSET, 5.0 + 0.8 + 0.25).late


def test_each_commander_has_its_own_lag():
    rule = SetpointDelay(0.3)
    steady(rule, 0.0, 2.0, 0.01, who="ada")
    # bob's clock is 5 s behind ada's: his first setpoint learns his own lag
    assert not rule.judge("bob", 2.0 + OFFSET - 5.0, 2.01).late
    assert not rule.judge("bob", 2.1 + OFFSET - 5.0, 2.11).late
    assert rule.judge("bob", 2.2 + OFFSET - 5.0, 2.9).late
    assert not rule.judge("ada", 2.2 + OFFSET, 2.21).late


def test_the_window_forgets_old_minima():
    rule = SetpointDelay(0.3, window_s=10.0)
    steady(rule, 0.0, 2.0, 0.01)
    # the publisher's clock steps back 2 s: refused until the window has forgotten the old lag
    verdicts = steady(rule, 2.0, 14.0, 2.01)
    first_obeyed = next(i for i, v in enumerate(verdicts) if not v.late)
    # the old lags (2 s of them) are forgotten 10 s of stream after they arrived
    assert 10.0 - 2.0 <= first_obeyed * PERIOD <= 10.0 + PERIOD
    assert not any(v.late for v in verdicts[first_obeyed:])


def test_a_setpoint_without_a_send_time_is_admitted():
    rule = SetpointDelay(0.3)
    steady(rule, 0.0, 1.0, 0.01)
    assert not rule.judge("ada", None, 50.0).late


@pytest.mark.parametrize("bad", [0.0, -1.0, float("nan"), float("inf")])
def test_the_threshold_is_validated(bad):
    with pytest.raises(ValueError, match="threshold_s"):
        SetpointDelay(bad)


def test_the_attachment_carries_the_send_time_and_reads_older_ones():
    assert origin_of(commander_attachment("ada", 1700000000.25)) == ("ada", 1700000000.25)
    assert origin_of(commander_attachment("ada")) == ("ada", None)
    assert origin_of(b"commander=ada") == ("ada", None)  # an older publisher's
    assert commander_of(commander_attachment("ada", 12.5)) == "ada"
    assert origin_of(b"commander=ada\nsent=nan") == ("ada", None)
    assert origin_of(b"commander=ada\nsent=x")[1] is None
    assert origin_of(None) == ("", None) and origin_of(b"other") == ("", None)
