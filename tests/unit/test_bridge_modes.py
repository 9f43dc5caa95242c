"""Mode names <-> custom_mode for PX4 and ArduCopter (MAVROS spellings)."""

from __future__ import annotations

import pytest
from pymavlink import mavutil

from dronewrapper_bridge_mavlink import modes


def test_px4_custom_mode_round_trip_matches_pymavlink_map():
    # pymavlink's own PX4 table: name -> (base_mode, main, sub)
    for short, (_base, main, sub) in mavutil.px4_map.items():
        custom = (main << 16) | (sub << 24)
        name = modes.mode_name(modes.AUTOPILOT_PX4, custom)
        assert modes.set_mode_params(modes.AUTOPILOT_PX4, name).param2 == main
        assert modes.set_mode_params(modes.AUTOPILOT_PX4, name).param3 == sub
        assert modes.canonical_mode(modes.AUTOPILOT_PX4, short) == name


@pytest.mark.parametrize(
    ("custom", "name"),
    [
        (6 << 16, "OFFBOARD"),
        ((4 << 16) | (6 << 24), "AUTO.LAND"),
        ((4 << 16) | (3 << 24), "AUTO.LOITER"),
        (3 << 16, "POSCTL"),
        ((4 << 16) | (5 << 24), "AUTO.RTL"),
    ],
)
def test_px4_names(custom, name):
    assert modes.mode_name(modes.AUTOPILOT_PX4, custom) == name


def test_arducopter_matches_pymavlink_table():
    for number, name in mavutil.mode_mapping_acm.items():
        if name in modes.ARDUCOPTER_MODES:
            assert modes.mode_name(modes.AUTOPILOT_ARDUPILOT, number) == name
            params = modes.set_mode_params(modes.AUTOPILOT_ARDUPILOT, name)
            assert (params.param1, params.param2) == (1.0, float(number))
    assert modes.mode_name(modes.AUTOPILOT_ARDUPILOT, 4) == "GUIDED"
    assert modes.GUIDED_MODE[modes.AUTOPILOT_ARDUPILOT] == "GUIDED"


def test_aliases_and_case():
    assert modes.canonical_mode(modes.AUTOPILOT_PX4, "offboard") == "OFFBOARD"
    assert modes.canonical_mode(modes.AUTOPILOT_PX4, "LAND") == "AUTO.LAND"
    assert modes.canonical_mode(modes.AUTOPILOT_PX4, "hold") == "AUTO.LOITER"
    assert modes.canonical_mode(modes.AUTOPILOT_ARDUPILOT, "AUTO.LAND") == "LAND"


def test_unknown_mode_lists_valid_ones():
    with pytest.raises(ValueError, match=r"valid modes: .*OFFBOARD"):
        modes.canonical_mode(modes.AUTOPILOT_PX4, "WARP")
    with pytest.raises(ValueError, match="GUIDED"):
        modes.canonical_mode(modes.AUTOPILOT_ARDUPILOT, "OFFBOARD")


def test_unknown_custom_mode_reported_like_mavros():
    assert modes.mode_name(modes.AUTOPILOT_PX4, 99 << 16) == f"CMODE({99 << 16})"


def test_autopilot_kind():
    assert modes.autopilot_kind(12) == "px4"
    assert modes.autopilot_kind(3) == "ardupilotmega"
    assert modes.autopilot_kind(0) == "generic"
    assert modes.is_guided("OFFBOARD") and modes.is_guided("GUIDED")
    assert not modes.is_guided("AUTO.LAND")


def test_holds_on_the_ground_only_in_offboard():
    """PX4's OFFBOARD needs a stream on the ground; ArduCopter's GUIDED must not get one."""
    assert modes.holds_on_the_ground("OFFBOARD")
    assert not modes.holds_on_the_ground("GUIDED") and not modes.holds_on_the_ground("LOITER")
