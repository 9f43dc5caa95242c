"""A refused setpoint stream is told to its commander at once, then about once a second with
how many refusals each message stands for (services/bridge_base refusals.py); the shared
core's lease and late-setpoint rules tell the commander they refuse (core_driver.py)."""

from __future__ import annotations

import logging
from dataclasses import dataclass, field

import pytest

from dronewrapper.msgs import registry
from dronewrapper_bridge_base.core_driver import PureCore
from dronewrapper_bridge_base.refusals import MAX_KEYS, RefusalThrottle


@dataclass
class Outbox:
    samples: list = field(default_factory=list)


def test_the_first_refusal_is_published_at_once_then_one_a_second_with_the_count():
    throttle = RefusalThrottle(period_s=1.0)
    counts = []
    for i in range(90):  # 3 s of a 30 Hz stream
        now = i / 30
        counts.append((now, throttle.admit(now, "ada", "lease", "setpoint", "command_lease", "x")))
    published = [(now, count) for now, count in counts if count]
    assert published[0] == (0.0, 1)
    assert len(published) == 3 and throttle.published == 3
    assert [count for _, count in published[1:]] == [30, 30]
    assert throttle.refused == 90


def test_another_commander_kind_or_limit_is_published_at_once():
    throttle = RefusalThrottle()
    assert throttle.admit(0.0, "ada", "envelope", "setpoint", "fence", "a") == 1
    assert throttle.admit(0.01, "ada", "envelope", "setpoint", "fence", "b") == 0
    assert throttle.admit(0.02, "bob", "envelope", "setpoint", "fence", "a") == 1
    assert throttle.admit(0.03, "ada", "envelope", "setpoint", "max_altitude", "a") == 1
    assert throttle.admit(0.04, "ada", "late", "setpoint", "late_setpoint_s", "a") == 1


def test_without_a_limit_refusals_differing_only_in_figures_are_one_stream():
    throttle = RefusalThrottle()
    assert throttle.admit(0.0, "ada", "validation", "setpoint", "", "speed 21.5 m/s > 20") == 1
    assert throttle.admit(0.1, "ada", "validation", "setpoint", "", "speed 23 m/s > 20") == 0
    assert throttle.admit(0.2, "ada", "validation", "setpoint", "", "yaw_rate 9 > 6.3") == 1


def test_streams_are_forgotten_beyond_the_most_recent_and_the_period_is_checked():
    throttle = RefusalThrottle()
    for n in range(MAX_KEYS + 1):
        throttle.admit(0.0, f"c{n}", "lease", "setpoint", "command_lease", "")
    assert throttle.admit(0.1, "c0", "lease", "setpoint", "command_lease", "") == 1  # forgotten
    with pytest.raises(ValueError, match="period_s"):
        RefusalThrottle(period_s=0.0)


def test_the_cores_lease_and_late_rules_tell_the_refused_commander():
    core = PureCore(0.0, Outbox, logging.getLogger("test"), lease_ttl_s=10.0)
    core.publish_state = lambda **_: None
    core._at(100.0, 1_700_000_100.0)
    assert core.admit_setpoint("alice", 1_700_000_100.0)
    assert not core.admit_setpoint("bob", 1_700_000_100.0)
    ((topic, told),) = core.take().samples
    assert topic is registry.REFUSAL and told.header.stamp == 1_700_000_100.0
    assert (told.commander, told.kind, told.limit) == ("bob", "lease", "command_lease")
    core._at(100.5, 1_700_000_100.5)
    assert not core.admit_setpoint("alice", 1_700_000_099.5)  # 1 s on the way: late
    ((_, late),) = core.take().samples
    assert (late.commander, late.kind, late.limit) == ("alice", "late", "late_setpoint_s")
    assert "later than its usual lag" in late.message
