"""What changed while the autopilot link was down is named when it returns (issue 12 item 11)."""

from __future__ import annotations

from dronewrapper.msgs.mavros import State
from dronewrapper_bridge_mavlink.link_gap import gap_changes, gap_report


def state(**kw) -> State:
    base = {"connected": True, "armed": True, "mode": "OFFBOARD", "system_status": 4}
    return State(**{**base, **kw})


def test_a_failsafe_during_the_gap_is_reported():
    report = gap_report(state(), state(mode="AUTO.RTL", system_status=5), 12.34)
    assert report == (
        "while the autopilot link was down (12.3 s): mode OFFBOARD -> AUTO.RTL, "
        "system status ACTIVE -> CRITICAL"
    )


def test_a_disarm_is_named():
    assert gap_changes(state(), state(armed=False, mode="AUTO.LAND")) == [
        "mode OFFBOARD -> AUTO.LAND",
        "disarmed",
    ]


def test_nothing_changed_or_no_history_reports_nothing():
    assert gap_report(state(), state(), 4.0) is None
    assert gap_report(None, state(mode="AUTO.RTL"), 4.0) is None
