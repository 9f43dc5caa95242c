"""The controller yields to a landing it did not order (pure rule)."""

from __future__ import annotations

import pytest

from dronewrapper.msgs.mavros import (
    LANDED_STATE_IN_AIR,
    LANDED_STATE_LANDING,
    LANDED_STATE_ON_GROUND,
    LANDED_STATE_UNDEFINED,
)
from dronewrapper_controller.yielding import ForeignLanding


@pytest.mark.parametrize(
    ("mode", "landed", "says"),
    [
        ("AUTO.LAND", LANDED_STATE_IN_AIR, "AUTO.LAND"),
        ("LAND", LANDED_STATE_IN_AIR, "LAND"),
        ("AUTO.RTL", LANDED_STATE_IN_AIR, "AUTO.RTL"),
        ("OFFBOARD", LANDED_STATE_LANDING, "landing, ordered by another commander"),
        ("OFFBOARD", LANDED_STATE_ON_GROUND, "landed, ordered by another commander"),
    ],
)
def test_a_landing_seen_in_flight_is_a_reason_to_yield(mode, landed, says):
    rule = ForeignLanding()
    assert rule.reason("OFFBOARD", LANDED_STATE_IN_AIR) is None  # servoing in flight
    reason = rule.reason(mode, landed)
    assert reason is not None and says in reason


def test_on_the_ground_before_any_flight_there_is_nothing_to_yield_to():
    rule = ForeignLanding()
    assert rule.reason(None, None) is None
    assert rule.reason("AUTO.LAND", LANDED_STATE_ON_GROUND) is None  # PX4 idle after a landing
    assert rule.reason("POSCTL", LANDED_STATE_UNDEFINED) is None
    assert rule.reason("OFFBOARD", LANDED_STATE_IN_AIR) is None
    assert rule.reason("OFFBOARD", LANDED_STATE_ON_GROUND) is not None  # now it flew
