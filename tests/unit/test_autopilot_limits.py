"""The autopilot's return altitude and fence action follow the envelope
(bridge_mavlink/autopilot_limits.py): a return never climbs above the ceiling, and the fence
the autopilot fires takes the envelope's breach action."""

from __future__ import annotations

import pytest

from dronewrapper.envelope import Envelope
from dronewrapper_bridge_mavlink import autopilot_limits as al


def test_px4_return_altitude_is_under_the_ceiling_and_the_fence_acts_as_asked():
    params = {name: value for name, value, _ in al.wanted("px4", Envelope(max_altitude=15.0))}
    assert params == {"RTL_RETURN_ALT": 14.0, "RTL_DESCEND_ALT": 10.0, "GF_ACTION": 3.0}
    low = Envelope(max_altitude=6.0, breach_action="land")
    params = {name: value for name, value, _ in al.wanted("px4", low)}
    assert params == {"RTL_RETURN_ALT": 5.0, "RTL_DESCEND_ALT": 5.0, "GF_ACTION": 5.0}
    params = {name: value for name, value, _ in al.wanted("px4", Envelope())}  # 120 m
    assert params["RTL_RETURN_ALT"] == 30.0  # PX4's default is under it: kept


def test_ardupilot_return_altitude_is_in_centimetres():
    envelope = Envelope(max_altitude=10.0, breach_action="hold")
    assert al.wanted("ardupilotmega", envelope) == [
        ("RTL_ALT", 900.0, True),
        ("FENCE_ACTION", 4.0, True),
    ]


@pytest.mark.parametrize("ceiling, expected", [(2.5, 2.0), (3.5, 2.5), (40.0, 30.0)])
def test_return_altitude_bounds(ceiling, expected):
    assert al.return_altitude(Envelope(max_altitude=ceiling), 30.0) == expected
