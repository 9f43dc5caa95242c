"""Stream health judged against the registry (pure): rates, ages, clock skew, bandwidth."""

import pytest

from dronewrapper.doctor import Heard, bridge_streams, describe_drone, stream_findings
from dronewrapper.health import (
    FAIL,
    OK,
    WARN,
    StreamLog,
    bandwidth_advice,
    clock_advice,
    describe_stream,
    is_stale,
    judge_stream,
    median_rate,
    stale_after,
)
from dronewrapper.msgs.mavros import State
from dronewrapper.msgs.registry import LOCAL_POSE, STATE
from dronewrapper.msgs.sensor import BatteryState


def log_of(times, skew=0.01):
    log = StreamLog()
    for t in times:
        log.add(t, skew, 100)
    return log


def test_median_rate_ignores_one_stall():
    times = [i * 0.02 for i in range(50)] + [2.0] + [2.0 + i * 0.02 for i in range(1, 50)]
    assert median_rate(times) == pytest.approx(50.0)
    assert median_rate([1.0]) == 0.0


def test_a_stream_at_its_rate_is_ok_and_a_slow_one_is_named():
    fast = judge_stream(
        "drone/mavros/local_position/pose", 30.0, log_of([i / 50 for i in range(100)]), 2.0
    )
    assert fast.verdict == OK and fast.rate_hz == pytest.approx(50.0)
    slow = judge_stream(
        "drone/mavros/local_position/pose", 30.0, log_of([i / 5 for i in range(10)]), 2.0
    )
    assert slow.verdict == WARN and "5.0 Hz, expected >= 30 Hz" in slow.note
    missing = judge_stream("drone/mavros/battery", 1.0, StreamLog(), 2.0)
    assert missing.verdict == FAIL and "nothing arrived" in missing.note
    stopped = judge_stream("drone/mavros/state", 1.0, log_of([0.0, 1.0, 2.0]), 8.0)
    assert stopped.verdict == WARN and "stopped 6.0 s ago" in stopped.note


def test_event_streams_have_no_rate_to_meet():
    assert judge_stream("drone/mavros/statustext/recv", 0.0, StreamLog(), 5.0).verdict == OK


def test_clock_skew_and_bandwidth_advice():
    assert clock_advice([0.003, 0.004])[0] == OK
    verdict, text = clock_advice([-0.4, -0.5])
    assert verdict == WARN and "ahead" in text and "chrony" in text
    assert clock_advice([])[0] == WARN
    verdict, text = bandwidth_advice(20.0)
    assert verdict == WARN and "compressed_images=True" in text
    assert bandwidth_advice(2000.0)[0] == OK
    assert bandwidth_advice(0.0)[0] == FAIL


def test_bridge_streams_come_from_the_registry():
    keys = bridge_streams("drone1")
    assert STATE.key("drone1") in keys and LOCAL_POSE.key("drone1") in keys
    assert not any("setpoint" in key or "image" in key for key in keys)


def test_findings_include_bridge_streams_never_heard_but_not_a_missing_gps():
    heard = Heard(
        logs={STATE.key("drone"): log_of([0.0, 0.5, 1.0])},
        topics={STATE.key("drone"): STATE},
        latest={},
        end=1.2,
    )
    by_key = {h.key: h for h in stream_findings(heard)}
    assert by_key["drone/mavros/battery"].verdict == FAIL
    assert "drone/mavros/global_position/global" not in by_key


def test_describe_drone_says_kind_mode_battery_and_link():
    latest = {
        "drone/mavros/state": State(connected=True, armed=True, mode="OFFBOARD", autopilot="px4"),
        "drone/mavros/battery": BatteryState(percentage=0.87),
    }
    verdict, text = describe_drone("drone", ["bridge_mavlink", "sim"], latest)
    assert verdict == OK
    assert text == (
        "drone 'drone' (px4): connected, mode OFFBOARD, armed, battery 87 %; "
        "alive: bridge_mavlink, sim"
    )
    assert describe_drone("drone", ["bridge_tello"], {})[0] == FAIL
    assert describe_drone("laptop", ["station"], {})[0] == OK


def test_one_freshness_rule_from_the_declared_rate():
    """Stale after five registry periods, never sooner than 0.5 s; event streams never."""
    assert stale_after(LOCAL_POSE.rate_hz) == 0.5  # 30 Hz: the floor
    assert stale_after(STATE.rate_hz) == pytest.approx(5.0)  # 1 Hz: five periods
    assert stale_after(0.0) == float("inf")
    assert not is_stale(30.0, 0.4) and is_stale(30.0, 0.6)
    assert not is_stale(0.0, 1e9)
    # doctor judges a stream stopped by the same rule
    fresh = judge_stream("drone/mavros/state", 1.0, log_of([0.0, 1.0, 2.0]), 6.9)
    assert fresh.verdict == OK
    stopped = judge_stream("drone/mavros/state", 1.0, log_of([0.0, 1.0, 2.0]), 7.1)
    assert stopped.verdict == WARN and "stale after 5 s" in stopped.note


def test_a_stream_is_described_against_its_declared_rate():
    log = log_of([i / 30 for i in range(30)])
    line = describe_stream(judge_stream(LOCAL_POSE.key("drone"), 30.0, log, 29 / 30 + 0.1))
    assert line == ("drone/mavros/local_position/pose: 30.0 Hz (declared 30 Hz), newest 0.10 s old")
    text = describe_stream(judge_stream("drone/mavros/statustext/recv", 0.0, log_of([1.0]), 3.0))
    assert text == "drone/mavros/statustext/recv: - (event-driven), newest 2.00 s old"
    slow = describe_stream(judge_stream("drone/mavros/battery", 1.0, StreamLog(), 2.0))
    assert slow == "drone/mavros/battery: - (declared 1 Hz): nothing arrived (expected >= 1 Hz)"
