"""A return to a rally point never climbs above the ceiling (bridge_mavlink/rally_returns.py
and autopilot_limits.py): ArduCopter's rule (``ModeRTL::compute_return_target``: the highest of
the point's altitude, ``RTL_ALT_M`` and the start plus ``RTL_CLIMB_MIN_M``, then
``RTL_ALT_FINAL_M`` over the point) with the parameters the bridge keeps, a rally point above
the return altitude refused on ArduCopter before anything is sent, and a new envelope that
would put an uploaded rally point out of reach refused, on both autopilots."""

from __future__ import annotations

import math

import pytest
from bridge_core_rig import ARDUPILOT, OFFBOARD, CoreRig
from pymavlink.dialects.v20 import common as mavlink
from test_bridge_rally import HOME, MISSION, RALLY, answer, at, rally

from dronewrapper.envelope import Envelope
from dronewrapper.msgs.mission import EnvelopeSet, WaypointPush
from dronewrapper.runtime import ServiceError
from dronewrapper_bridge_mavlink import autopilot_limits as al
from dronewrapper_bridge_mavlink import missions
from dronewrapper_bridge_mavlink import rally_returns as rr

ARDU_GUIDED = 4
USER_SETTINGS = {"RTL_ALT_M": 30.0, "RTL_ALT_FINAL_M": 20.0, "RTL_CLIMB_MIN_M": 5.0}
"""An ArduCopter a user set up for a high site: all three above a 15 m ceiling."""


def test_ardupilots_return_flies_at_the_highest_of_point_return_altitude_and_climb():
    assert rr.ardupilot_peak(5.0, 14.0) == 14.0  # RTL_ALT_M over a low rally point
    assert rr.ardupilot_peak(14.5, 14.0) == 14.5  # a high rally point wins
    assert rr.ardupilot_peak(5.0, 14.0, start_up=13.0, climb_min=2.0) == 15.0
    assert rr.ardupilot_peak(-3.0, 0.0) == rr.ARDUPILOT_RTL_ALT_MIN_M
    assert rr.ardupilot_peak(5.0, 10.0, start_up=12.0) == 12.0  # it never descends first
    assert rr.px4_peak(5.0, 14.0) == 19.0


@pytest.mark.parametrize("ceiling", [3.0, 15.0, 40.0])
def test_with_the_parameters_the_bridge_keeps_no_ardupilot_return_climbs_above_the_ceiling(
    ceiling,
):
    """The user's settings after :func:`al.wanted` is applied; every rally point the bridge
    accepts and every start under the ceiling's return altitude."""
    envelope = Envelope(max_altitude=ceiling)
    kept = dict(USER_SETTINGS)
    for name, value, how in al.wanted("ardupilotmega", envelope):
        if name in kept:
            write = al.to_write(kept[name], value, how)
            kept[name] = kept[name] if write is None else write
    bound = al.return_altitude(envelope)
    assert ("RTL_ALT_TYPE", 0.0, al.EXACTLY) in al.wanted("ardupilotmega", envelope)
    assert kept["RTL_ALT_FINAL_M"] <= bound  # its last move over the point, never a climb
    for point_up in (0.0, bound / 2, bound):
        rr.check([rally(5.0, 5.0, point_up)], envelope, HOME, ardupilot=True, return_alt=bound)
        for start_up in (0.5, bound / 2, bound):
            peak = rr.ardupilot_peak(point_up, kept["RTL_ALT_M"], start_up, kept["RTL_CLIMB_MIN_M"])
            assert peak <= bound < ceiling, (point_up, start_up, kept)


def ardupilot_rig(ceiling: float = 15.0) -> CoreRig:
    rig = CoreRig(autopilot=ARDUPILOT, upload_fence=False, envelope=Envelope(max_altitude=ceiling))
    rig.connect(mode=ARDU_GUIDED, armed=True, flying=True)
    rig.run(0.2)
    lat, lon = round(HOME[0] * 1e7), round(HOME[1] * 1e7)
    rig.deliver(
        mavlink.MAVLink_home_position_message(
            lat, lon, 488000, 0.0, 0.0, 0.0, [1.0, 0.0, 0.0, 0.0], 0.0, 0.0, 0.0
        )
    )
    rig.run(0.1)
    return rig


def acknowledged(rig: CoreRig, push) -> None:
    """The autopilot takes the mission and rally lists of ``push``, which then succeeds."""
    answer(rig, MISSION)
    answer(rig, RALLY)
    assert push.result().success


def with_ceiling(rig: CoreRig, max_altitude: float):
    """The bridge asked for an envelope of ``max_altitude`` (m); its pending call."""
    op = rig.call(missions.set_envelope, EnvelopeSet(envelope=Envelope(max_altitude=max_altitude)))
    rig.run(0.1)
    return op


def test_on_ardupilot_a_rally_point_above_the_return_altitude_is_refused():
    """ArduCopter returns at a rally point's own altitude when it is the higher: 14.5 m under
    a 15 m ceiling is refused (the return altitude is kept at 14 m), naming the point."""
    rig = ardupilot_rig()
    request = WaypointPush(waypoints=[at(10, 0, 6)], rally=[rally(30, 0, 5), rally(-20, 25, 14.5)])
    op = rig.call(missions.push, request)
    rig.run(0.1)
    with pytest.raises(
        ServiceError, match=r"rally point 1: an ArduCopter return there flies at its 14.5 m"
    ):
        op.result()
    assert not rig.sent_since(-math.inf, "MISSION_COUNT")
    op = rig.call(missions.push, WaypointPush(waypoints=[at(10, 0, 6)], rally=[rally(30, 0, 14)]))
    rig.run(0.1)
    acknowledged(rig, op)


def test_a_new_envelope_that_puts_an_uploaded_rally_point_out_of_reach_is_refused():
    rig = ardupilot_rig(ceiling=30.0)
    op = rig.call(missions.push, WaypointPush(waypoints=[at(10, 0, 6)], rally=[rally(30, 0, 12)]))
    rig.run(0.1)
    acknowledged(rig, op)
    op = with_ceiling(rig, 12.0)
    with pytest.raises(ServiceError, match=r"envelope refused: rally point 0: an ArduCopter"):
        op.result()
    assert rig.core.missions.envelope.max_altitude == 30.0
    op = with_ceiling(rig, 13.0)
    assert op.result().envelope.max_altitude == 13.0


def test_on_px4_a_lower_ceiling_under_an_uploaded_rally_points_return_is_refused():
    rig = CoreRig(upload_fence=False).connect(mode=OFFBOARD, armed=True, flying=True)
    rig.run(0.2)
    rig.deliver(
        mavlink.MAVLink_home_position_message(
            round(HOME[0] * 1e7), round(HOME[1] * 1e7), 488000, 0.0, 0.0, 0.0,
            [1.0, 0.0, 0.0, 0.0], 0.0, 0.0, 0.0,
        )
    )  # fmt: skip
    op = rig.call(missions.push, WaypointPush(waypoints=[at(10, 0, 6)], rally=[rally(30, 0, 5)]))
    rig.run(0.1)
    rig.param("RTL_RETURN_ALT", 10.0, mavlink.MAV_PARAM_TYPE_REAL32)
    rig.run(0.1)
    acknowledged(rig, op)
    op = with_ceiling(rig, 12.0)
    rig.param("RTL_RETURN_ALT", 10.0, mavlink.MAV_PARAM_TYPE_REAL32)
    rig.run(0.1)
    with pytest.raises(ServiceError, match=r"envelope refused: rally point 0: .* climbs to 15 m"):
        op.result()
