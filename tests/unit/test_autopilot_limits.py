"""The autopilot's return altitude and fence action follow the envelope
(bridge_mavlink/autopilot_limits.py): a return never climbs above the ceiling (a lower value
the autopilot holds is kept), and the fence the autopilot fires takes the envelope's breach
action."""

from __future__ import annotations

import pytest
from bridge_core_rig import ARDUPILOT, CoreRig

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


def test_ardupilot_return_heights_in_metres_and_centimetres_stay_under_the_ceiling():
    """The return altitude, the final height over the destination (a higher one climbs
    there), no added climb, heights above home (rally_returns.py has the rule)."""
    assert al.wanted("ardupilotmega", Envelope(max_altitude=10.0, breach_action="hold")) == [
        ("RTL_ALT_M", 9.0, al.AT_MOST),
        ("RTL_ALT", 900.0, al.AT_MOST),
        ("FENCE_ACTION", 4.0, al.EXACTLY),
        ("RTL_ALT_TYPE", 0.0, al.EXACTLY),
        ("RTL_ALT_FINAL_M", 9.0, al.AT_MOST),
        ("RTL_ALT_FINAL", 900.0, al.AT_MOST),
        ("RTL_CLIMB_MIN_M", 0.0, al.AT_MOST),
        ("RTL_CLIMB_MIN", 0.0, al.AT_MOST),
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


def _sync_on_ardupilot(
    has: dict[str, tuple[float, int]], rig: CoreRig | None = None
) -> tuple[str, dict[str, float]]:
    """Run :func:`al.sync` on a connected ArduPilot core (``rig``'s, or a new one) that
    answers for the parameters in ``has`` (name -> (value, MAV_PARAM_TYPE)) and stays silent
    for any other (as ArduPilot does for a name it does not have); its result and the values
    it was asked to write."""
    if rig is None:
        rig = CoreRig(autopilot=ARDUPILOT).connect()
        rig.run(0.5)
    since = rig.now
    op = rig.call(lambda core, _request: al.sync_steps(core), None)
    written: dict[str, float] = {}
    answered = 0
    for _ in range(400):  # 40 s of bus time at most; the exchange ends long before
        if op.done:
            break
        rig.run(0.1)
        sent = rig.sent_since(since)
        for msg in sent[answered:]:
            name = getattr(msg, "param_id", "")
            if msg.get_type() == "PARAM_SET" and name in has:
                written[name] = msg.param_value
                has[name] = (msg.param_value, has[name][1])
            if name in has and msg.get_type() in ("PARAM_REQUEST_READ", "PARAM_SET"):
                rig.param(name, *has[name])
        answered = len(sent)
    assert op.done
    return op.reply, written


REAL32, INT16, INT8 = 9, 4, 2  # MAV_PARAM_TYPE
ARDUPILOT_4_8 = {  # ArduCopter 4.8 as a user left it: its return climbs 5 m, ends at 130 m
    "RTL_ALT_M": (150.0, REAL32),
    "FENCE_ACTION": (1.0, INT8),
    "RTL_ALT_TYPE": (1.0, INT8),
    "RTL_ALT_FINAL_M": (130.0, REAL32),
    "RTL_CLIMB_MIN_M": (5.0, REAL32),
}


def test_ardupilot_4_8_gets_its_return_heights_in_metres():
    problem, written = _sync_on_ardupilot(dict(ARDUPILOT_4_8))  # no RTL_ALT etc. any more
    assert problem == ""
    assert written == {  # under the 120 m default ceiling
        "RTL_ALT_M": 119.0,
        "RTL_ALT_TYPE": 0.0,
        "RTL_ALT_FINAL_M": 119.0,
        "RTL_CLIMB_MIN_M": 0.0,
    }


def test_the_names_an_ardupilot_does_not_have_are_asked_once():
    """4.8 has no RTL_ALT, RTL_ALT_FINAL, RTL_CLIMB_MIN: each costs the read's attempts once,
    not at every new envelope."""
    rig = CoreRig(autopilot=ARDUPILOT).connect()
    rig.run(0.5)
    _sync_on_ardupilot(dict(ARDUPILOT_4_8), rig)
    rig.core.missions.envelope = Envelope(max_altitude=15.0)
    since = rig.now
    problem, written = _sync_on_ardupilot(dict(ARDUPILOT_4_8), rig)
    assert problem == "" and written["RTL_ALT_M"] == 14.0
    asked = {m.param_id for m in rig.sent_since(since) if m.get_type() == "PARAM_REQUEST_READ"}
    assert asked == set(ARDUPILOT_4_8)


def test_ardupilot_before_4_8_gets_rtl_alt_in_centimetres():
    problem, written = _sync_on_ardupilot(
        {
            "RTL_ALT": (15000.0, INT16),
            "FENCE_ACTION": (1.0, INT8),
            "RTL_ALT_TYPE": (0.0, INT8),
            "RTL_ALT_FINAL": (0.0, INT16),
            "RTL_CLIMB_MIN": (200.0, INT16),
        }
    )
    assert problem == "" and written == {"RTL_ALT": 11900.0, "RTL_CLIMB_MIN": 0.0}


def test_an_ardupilot_with_neither_return_altitude_says_so():
    has = {k: v for k, v in ARDUPILOT_4_8.items() if k != "RTL_ALT_M"}
    problem, _ = _sync_on_ardupilot(has)
    assert problem == "RTL_ALT_M / RTL_ALT: no such parameter answered"
