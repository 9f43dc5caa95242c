"""The autopilot's return altitude and fence action follow the envelope
(bridge_mavlink/autopilot_limits.py): a return never climbs above the ceiling (a lower value
the autopilot holds is kept), and the fence the autopilot fires takes the envelope's breach
action."""

from __future__ import annotations

import pytest

from dronewrapper.envelope import Envelope
from dronewrapper_bridge_mavlink import autopilot_limits as al


def test_px4_return_altitude_is_capped_under_the_ceiling_and_the_fence_acts_as_asked():
    assert al.wanted("px4", Envelope(max_altitude=15.0)) == [
        ("RTL_RETURN_ALT", 14.0, al.AT_MOST),
        ("RTL_DESCEND_ALT", 14.0, al.AT_MOST),
        ("GF_ACTION", 3.0, al.EXACTLY),
    ]
    low = dict(
        (n, v) for n, v, _ in al.wanted("px4", Envelope(max_altitude=6.0, breach_action="land"))
    )
    assert low == {"RTL_RETURN_ALT": 5.0, "RTL_DESCEND_ALT": 5.0, "GF_ACTION": 5.0}


def test_ardupilot_return_altitude_is_in_centimetres():
    assert al.wanted("ardupilotmega", Envelope(max_altitude=10.0, breach_action="hold")) == [
        ("RTL_ALT", 900.0, al.AT_MOST),
        ("FENCE_ACTION", 4.0, al.EXACTLY),
    ]


def test_only_a_value_above_the_cap_or_a_different_action_is_written():
    assert al.to_write(30.0, 14.0, al.AT_MOST) == 14.0  # PX4's default 30 m over a 15 m ceiling
    assert al.to_write(6.0, 14.0, al.AT_MOST) is None  # the user's lower return is kept
    assert al.to_write(None, 14.0, al.AT_MOST) == 14.0
    assert al.to_write(2.0, 3.0, al.EXACTLY) == 3.0
    assert al.to_write(3.0, 3.0, al.EXACTLY) is None


@pytest.mark.parametrize("ceiling, expected", [(2.5, 2.0), (3.5, 2.5), (40.0, 39.0)])
def test_return_altitude_bounds(ceiling, expected):
    assert al.return_altitude(Envelope(max_altitude=ceiling)) == expected
