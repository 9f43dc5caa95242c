"""Every rule of the bridge's contract, at its owner (the pure core), in given time.

Each test fails if its rule is taken out of the core (checked by deleting each one). Real
MAVLink bytes both ways (see bridge_core_rig.py); no sockets, no clock, milliseconds each.
"""

from __future__ import annotations

import math

import pytest
from bridge_core_rig import (
    ACCEPTED,
    ARDU_GUIDED,
    ARDUPILOT,
    ARM,
    AUTO_LAND,
    NAV_LAND,
    NAV_TAKEOFF,
    OFFBOARD,
    POSCTL,
    REJECTED,
    SET_MODE,
    CoreRig,
    int_bits,
)
from pymavlink.dialects.v20 import common as mavlink

from dronewrapper.msgs import mavros, registry
from dronewrapper.runtime import ServiceError
from dronewrapper_bridge_mavlink import operations as ops
from dronewrapper_bridge_mavlink import parameters

INT32 = mavlink.MAV_PARAM_TYPE_INT32


def flying_in_offboard(**config) -> CoreRig:
    """A PX4 airborne in OFFBOARD, commanded by a streaming app."""
    rig = CoreRig(**config).connect(mode=OFFBOARD, armed=True, flying=True)
    rig.run(1.0, stream=True)
    assert rig.core.failsafe.engaged
    return rig


# ---- take-off


def test_takeoff_while_flying_does_nothing():
    rig = CoreRig().connect(mode=AUTO_LAND, armed=True, flying=True)
    op = rig.call(ops.takeoff, mavros.CommandTOL.takeoff(10.0))
    assert op.done and op.result().success and op.result().message == "already flying"
    assert rig.commands(NAV_TAKEOFF) == []


def test_takeoff_on_the_ground_sends_nav_takeoff_and_enters_auto_takeoff():
    rig = CoreRig().connect()
    op = rig.call(ops.takeoff, mavros.CommandTOL.takeoff(3.0))
    (sent,) = rig.commands(NAV_TAKEOFF)
    assert not op.done
    rig.ack(NAV_TAKEOFF, ACCEPTED)
    assert op.done and op.result().success
    assert rig.core.current_state().mode == "AUTO.TAKEOFF"
    assert math.isnan(sent.param7)  # no home altitude known: PX4's default height
    assert "no home altitude" in op.result().message


@pytest.mark.parametrize("altitude", [0.0, -1.0])
def test_takeoff_altitude_out_of_range_is_a_bad_request(altitude):
    rig = CoreRig().connect()
    with pytest.raises(ValueError, match="altitude"):
        rig.call(ops.takeoff, mavros.CommandTOL.takeoff(altitude)).result()
    assert rig.commands(NAV_TAKEOFF) == []


def test_nothing_is_commanded_before_the_autopilot_is_heard():
    rig = CoreRig()
    with pytest.raises(ServiceError, match="not connected"):
        rig.call(ops.arming, mavros.CommandBool(value=True)).result()
    assert rig.sent_since(-math.inf, "COMMAND_LONG") == []


# ---- parameters


def test_px4_integer_parameters_are_their_bytes():
    rig = CoreRig().connect()
    op = rig.call(parameters.param_get, mavros.ParamGet(param_id="COM_RC_IN_MODE"))
    (request,) = rig.sent_since(-math.inf, "PARAM_REQUEST_READ")
    assert request.param_id == "COM_RC_IN_MODE"
    rig.param("COM_RC_IN_MODE", int_bits(4), INT32)
    assert op.result().value == mavros.ParamValue(integer=4, real=0.0, kind="integer")


def test_ardupilot_integer_parameters_are_float_values():
    rig = CoreRig(autopilot=ARDUPILOT).connect()
    op = rig.call(parameters.param_get, mavros.ParamGet(param_id="FS_THR_ENABLE"))
    rig.param("FS_THR_ENABLE", 4.0, INT32)
    assert op.result().value == mavros.ParamValue(integer=4, real=0.0, kind="integer")


def test_px4_integer_parameter_set_is_written_as_bytes_and_checked_on_the_echo():
    rig = CoreRig().connect()
    rig.param("COM_RC_IN_MODE", int_bits(1), INT32)  # known type: no read first
    request = mavros.ParamSet(param_id="COM_RC_IN_MODE", value=mavros.ParamValue(integer=2))
    op = rig.call(parameters.param_set, request)
    (written,) = rig.sent_since(-math.inf, "PARAM_SET")
    assert written.param_value == int_bits(2) and written.param_type == INT32
    rig.now += 0.01
    rig.param("COM_RC_IN_MODE", int_bits(2), INT32)
    assert op.result().success and op.result().value.integer == 2


def test_a_parameter_of_unknown_type_is_read_then_written_and_checked_on_the_echo():
    rig = CoreRig().connect()
    request = mavros.ParamSet(param_id="MPC_XY_VEL_MAX", value=mavros.ParamValue(real=5.0))
    op = rig.call(parameters.param_set, request)
    assert rig.sent_since(-math.inf, "PARAM_SET") == []  # its type first
    rig.param("MPC_XY_VEL_MAX", 12.0, mavlink.MAV_PARAM_TYPE_REAL32)
    (written,) = rig.sent_since(-math.inf, "PARAM_SET")
    assert not op.done, "the value read is not the echo of the write"
    rig.param("MPC_XY_VEL_MAX", written.param_value, mavlink.MAV_PARAM_TYPE_REAL32)
    assert op.result().success and op.result().value.real == 5.0


def test_unanswered_parameter_read_gives_up_after_its_attempts():
    rig = CoreRig(param_attempts=2, param_timeout=0.5).connect()
    op = rig.call(parameters.param_get, mavros.ParamGet(param_id="NOPE"))
    rig.run(1.2)
    assert op.done and not op.result().success
    assert len(rig.sent_since(-math.inf, "PARAM_REQUEST_READ")) == 2


# ---- modes


def test_refused_mode_reaches_the_caller_with_the_autopilots_reason():
    rig = CoreRig().connect()
    op = rig.call(ops.set_mode, mavros.SetMode(custom_mode="POSCTL"))
    rig.ack(SET_MODE, ACCEPTED)  # PX4's receiver: only "received"
    rig.text("Switching to Position is currently not available")
    rig.ack(SET_MODE, REJECTED)  # the commander's real answer
    rig.run(0.6)  # the reason is looked for up to reason_wait
    reply = op.result()
    assert not reply.mode_sent and reply.result == REJECTED
    assert "TEMPORARILY_REJECTED" in reply.message
    assert "Switching to Position is currently not available" in reply.message


def test_set_mode_answers_only_after_px4s_second_ack_so_nothing_arms_before_it():
    rig = CoreRig().connect()
    rig.run(1.5, stream=True)  # an app streams: no priming needed
    op = rig.call(ops.set_mode, mavros.SetMode(custom_mode="OFFBOARD"))
    assert rig.commands(SET_MODE), "DO_SET_MODE sent at once after the app's stream"
    rig.ack(SET_MODE, ACCEPTED)
    rig.run(0.5, stream=True)
    assert not op.done, "a first (provisional) ACCEPTED is not the answer"
    rig.ack(SET_MODE, ACCEPTED)
    assert op.done and op.result().mode_sent
    assert rig.core.current_state().mode == "OFFBOARD"


def test_a_mode_acked_once_must_show_in_heartbeat_or_it_failed():
    rig = CoreRig().connect()
    op = rig.call(ops.set_mode, mavros.SetMode(custom_mode="AUTO.LAND"))
    rig.ack(SET_MODE, ACCEPTED)
    rig.run(1.0)  # no second ack: final_ack_timeout passes
    assert not op.done
    rig.run(3.0)  # HEARTBEAT still shows AUTO.LOITER
    assert op.done and not op.result().mode_sent
    assert "still in AUTO.LOITER" in op.result().message


def test_offboard_is_asked_for_only_after_the_bridge_has_streamed_long_enough():
    rig = CoreRig(offboard_prime_s=1.2).connect(armed=False)
    op = rig.call(ops.set_mode, mavros.SetMode(custom_mode="OFFBOARD"))
    assert rig.commands(SET_MODE) == []
    rig.run(2.0)
    asked_at, sent = next((t, m) for t, m in rig.sent if m.get_type() == "COMMAND_LONG"
                          and m.command == SET_MODE)  # fmt: skip
    first_hold = next(t for t, m in rig.sent if m.get_type() == "SET_POSITION_TARGET_LOCAL_NED")
    assert asked_at - first_hold >= 1.2 and not op.done
    assert sent.param2 == 6  # PX4 main mode OFFBOARD


def test_offboard_without_a_pose_or_a_stream_is_refused():
    rig = CoreRig()
    rig.heartbeat()
    with pytest.raises(ServiceError, match="no local position"):
        rig.call(ops.set_mode, mavros.SetMode(custom_mode="OFFBOARD")).result()


def test_arming_refusal_carries_the_reason():
    rig = CoreRig().connect()
    op = rig.call(ops.arming, mavros.CommandBool(value=True))
    rig.text("Arming denied: Resolve system health failures")
    rig.ack(ARM, mavlink.MAV_RESULT_TEMPORARILY_REJECTED)
    assert "Arming denied: Resolve system health failures" in op.result().message


def test_an_unacknowledged_command_is_retried_with_its_confirmation_counter():
    rig = CoreRig(command_attempts=3, command_ack_timeout=0.5).connect()
    op = rig.call(ops.arming, mavros.CommandBool(value=True))
    rig.run(2.0)
    assert [m.confirmation for m in rig.commands(ARM)] == [0, 1, 2]
    assert op.done and "no COMMAND_ACK after 3 attempt(s)" in op.result().message


# ---- the failsafe contract


def test_setpoint_expiry_holds_the_pose():
    rig = flying_in_offboard()
    stopped = rig.now
    rig.run(1.0)
    assert rig.core.failsafe.state == "hold"
    assert rig.state().failsafe == "hold"
    holds = rig.setpoints(since=stopped + 0.6, mask=mavros.MASK_POSITION)
    assert len(holds) >= 10
    assert all(h.x == pytest.approx(0.0) and h.z == pytest.approx(-5.0) for h in holds)


def test_a_stale_setpoint_never_reaches_the_autopilot():
    rig = flying_in_offboard(setpoint_timeout=0.5)
    stopped = rig.now
    rig.run(2.0)
    late = [m for m in rig.setpoints(since=stopped + 0.55) if m.type_mask == mavros.MASK_VELOCITY]
    assert late == []


def test_a_forwarded_setpoint_is_not_sent_twice_in_one_stream_period():
    rig = flying_in_offboard()
    since = rig.now
    rig.run(1.0, stream=True)  # one setpoint per tick: forwarded, so the tick sends nothing
    assert len(rig.setpoints(since=since + 1e-6)) == 30


def test_a_duplicated_datagram_is_used_once():
    rig = CoreRig().connect()
    rig.now += 0.02
    datagram = rig.packed(mavlink.MAVLink_local_position_ned_message(5000, 1, 2, -3, 0, 0, 0))
    poses = len(rig.published(registry.LOCAL_POSE))
    for _ in range(3):
        rig.deliver_bytes(datagram)
    assert len(rig.published(registry.LOCAL_POSE)) == poses + 1
    assert rig.core.freshness.duplicates == 2


def test_commander_lost_lands():
    rig = flying_in_offboard(commander_lost_timeout=5.0)
    stopped = rig.now
    rig.run(4.5)
    assert rig.commands(NAV_LAND) == []
    rig.run(1.0)
    (land,) = rig.commands(NAV_LAND, since=stopped)
    rig.ack(NAV_LAND, ACCEPTED)
    assert rig.core.failsafe.state == "land"
    assert rig.core.current_state().mode == "AUTO.LAND"
    assert land.target_system == 1


@pytest.mark.parametrize("answer", [None, REJECTED])
def test_the_hold_streams_on_while_the_failsafe_land_is_unanswered_or_refused(answer):
    """Without the stream, PX4 would leave OFFBOARD on its own offboard-loss failsafe."""
    rig = flying_in_offboard(commander_lost_timeout=2.0)
    rig.run(2.5)
    assert len(rig.commands(NAV_LAND)) == 1
    asked = rig.now
    if answer is not None:
        rig.ack(NAV_LAND, answer)
    rig.run(4.0)  # heartbeats: still in OFFBOARD
    assert rig.core.failsafe.state == "land" and rig.core.current_state().mode == "OFFBOARD"
    times = [
        t for t, m in rig.sent if t >= asked and m.get_type() == "SET_POSITION_TARGET_LOCAL_NED"
    ]
    period = 1.0 / rig.core.config.stream_rate_hz
    gaps = [b - a for a, b in zip([asked, *times], [*times, rig.now], strict=False)]
    assert max(gaps) <= 1.5 * period, "the hold stopped while the landing was not under way"
    assert {m.type_mask for m in rig.setpoints(since=asked)} == {mavros.MASK_POSITION}


def test_commander_lost_action_return():
    rig = flying_in_offboard(commander_lost_action="return")
    rig.run(6.0)
    assert rig.commands(mavlink.MAV_CMD_NAV_RETURN_TO_LAUNCH)


def test_never_fight_the_pilot():
    rig = flying_in_offboard()
    rig.custom_mode = POSCTL  # the pilot's RC switch
    since = rig.now
    rig.run(8.0)
    texts = [t.text for t in rig.published(registry.STATUSTEXT)]
    assert any("not switching back" in t for t in texts)
    assert rig.core.failsafe.pilot_override
    assert rig.commands(NAV_LAND) == [] and rig.commands(SET_MODE) == []
    assert rig.setpoints(since=since + 0.5) == []


def test_guided_mode_re_entered_with_a_live_commander_applies_the_contract_again():
    rig = flying_in_offboard()
    rig.custom_mode = POSCTL
    rig.run(1.0, stream=True)
    assert rig.core.failsafe.pilot_override and not rig.core.failsafe.engaged
    rig.custom_mode = OFFBOARD  # a ground station switches back; the app still streams
    rig.run(1.0, stream=True)
    assert rig.core.failsafe.engaged and not rig.core.failsafe.pilot_override
    stopped = rig.now
    rig.run(1.0)
    assert rig.core.failsafe.state == "hold"
    rig.run(5.0)
    assert rig.commands(NAV_LAND, since=stopped)


def test_land_is_known_from_its_ack_no_spurious_hold():
    rig = flying_in_offboard()
    op = rig.call(ops.land, mavros.CommandTOL.land())
    rig.ack(NAV_LAND, ACCEPTED)
    landing = rig.now
    assert op.result().success and rig.core.current_state().mode == "AUTO.LAND"
    rig.run(0.9, heartbeat_hz=0)  # PX4's 1 Hz heartbeat has not shown AUTO.LAND yet
    rig.custom_mode = AUTO_LAND
    rig.run(1.0)
    assert rig.core.failsafe.state == ""
    assert {s.failsafe for s in rig.published(registry.STATE, since=landing)} == {""}
    assert rig.setpoints(since=landing, mask=mavros.MASK_POSITION) == []  # no hold


def test_ardupilot_takeoff_in_guided_is_not_overridden_by_a_hold():
    rig = CoreRig(autopilot=ARDUPILOT).connect(mode=ARDU_GUIDED, armed=True)
    since = rig.now
    op = rig.call(ops.takeoff, mavros.CommandTOL.takeoff(5.0))
    (sent,) = rig.commands(NAV_TAKEOFF)
    assert sent.param7 == 5.0  # ArduCopter: relative height
    rig.ack(NAV_TAKEOFF, ACCEPTED)
    rig.run(2.0)
    assert op.result().success and rig.setpoints(since=since) == []
