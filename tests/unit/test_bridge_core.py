"""The bridge core's logic beyond the contract rules: modes, connection, telemetry, ArduPilot.

Given time, real MAVLink bytes, no sockets; the wiring is tested in tests/integration.
"""

from __future__ import annotations

import math

import pytest
from bridge_core_rig import (
    ACCEPTED,
    ARDU_GUIDED,
    ARDU_LOITER,
    ARDUPILOT,
    NAV_LAND,
    OFFBOARD,
    SET_MODE,
    CoreRig,
    velocity,
)
from pymavlink.dialects.v20 import common as mavlink

from dronewrapper.msgs import registry
from dronewrapper.msgs.lease import LeaseRequest
from dronewrapper.msgs.mavros import (
    MASK_POSITION,
    CommandBool,
    CommandTOL,
    ParamSet,
    ParamValue,
    SetMode,
)
from dronewrapper.runtime import ServiceError
from dronewrapper_bridge_mavlink import operations as ops
from dronewrapper_bridge_mavlink import parameters

AUTO_RTL = (4 << 16) | (5 << 24)
REAL32, INT32 = mavlink.MAV_PARAM_TYPE_REAL32, mavlink.MAV_PARAM_TYPE_INT32


def test_unknown_mode_lists_the_valid_ones():
    rig = CoreRig().connect()
    with pytest.raises(ValueError, match="valid modes"):
        rig.call(ops.set_mode, SetMode(custom_mode="WARP9")).result()
    assert rig.commands(SET_MODE) == []


def test_px4s_second_ack_is_the_answer_not_a_duplicate():
    rig = CoreRig().connect()
    rig.run(1.5, stream=True)
    for mode in ("OFFBOARD", "AUTO.LOITER", "OFFBOARD"):
        rig.run(0.4, stream=True)  # past the duplicate-ack quiet time
        op = rig.call(ops.set_mode, SetMode(custom_mode=mode))
        rig.ack(SET_MODE, ACCEPTED)
        rig.ack(SET_MODE, ACCEPTED)
        assert op.result().mode_sent, op.result()
    assert rig.core.commands.acks.duplicates == 0


def test_a_mode_acked_once_is_confirmed_by_heartbeat():
    rig = CoreRig().connect()
    op = rig.call(ops.set_mode, SetMode(custom_mode="AUTO.LAND"))
    rig.ack(SET_MODE, ACCEPTED)
    rig.custom_mode = (4 << 16) | (6 << 24)
    rig.run(1.5)
    assert op.result().mode_sent and "confirmed by HEARTBEAT" in op.result().message


def test_commands_wait_for_each_other():
    rig = CoreRig().connect()
    first = rig.call(ops.arming, CommandBool(value=True))
    second = rig.call(ops.land, CommandTOL.land())
    assert rig.commands(NAV_LAND) == []  # one COMMAND_LONG exchange at a time
    rig.ack(mavlink.MAV_CMD_COMPONENT_ARM_DISARM, ACCEPTED)
    assert first.result().success
    rig.run(0.1)
    assert rig.commands(NAV_LAND)
    rig.ack(NAV_LAND, ACCEPTED)
    assert second.result().success


def test_heartbeat_loss_reports_disconnected_then_recovers():
    rig = CoreRig(heartbeat_timeout=3.0).connect()
    assert rig.state().connected
    lost = rig.now
    rig.run(3.5, heartbeat_hz=0)
    assert not rig.state().connected and not rig.core.connected
    with pytest.raises(ServiceError, match="not connected"):
        rig.call(ops.arming, CommandBool(value=True)).result()
    rig.heartbeat()
    assert rig.state().connected
    assert rig.published(registry.STATE, since=lost)  # published on change


def test_a_failsafe_during_a_link_gap_is_reported_when_the_link_returns():
    rig = CoreRig(heartbeat_timeout=1.0).connect(mode=OFFBOARD, armed=True)
    rig.run(1.5, heartbeat_hz=0)
    assert not rig.core.connected
    rig.custom_mode = AUTO_RTL  # PX4's data-link-loss failsafe
    rig.heartbeat()
    (report,) = [
        t.text
        for t in rig.published(registry.STATUSTEXT)
        if "while the autopilot link was down" in t.text
    ]
    assert "mode OFFBOARD -> AUTO.RTL" in report and report.startswith("bridge: ")


def test_on_connection_it_asks_for_message_rates_and_sends_a_gcs_heartbeat():
    rig = CoreRig().connect()
    rig.run(4.5)
    rates = rig.commands(mavlink.MAV_CMD_SET_MESSAGE_INTERVAL)
    asked = {int(m.param1) for m in rates}
    assert {mavlink.MAVLINK_MSG_ID_LOCAL_POSITION_NED, 31} <= asked  # 31: ATTITUDE_QUATERNION
    asked_rates = [m for m in rates if m.param2 > 0]
    assert len(asked_rates) == 3 * len(rig.core.config.message_rates)  # 3 rounds, 2 s apart
    beats = rig.sent_since(-math.inf, "HEARTBEAT")
    assert len(beats) == 5 and {b.type for b in beats} == {mavlink.MAV_TYPE_GCS}


def test_telemetry_is_published_in_enu():
    rig = CoreRig().connect()
    rig.pose(north=5.0, east=2.0, down=-3.0)
    p = rig.published(registry.LOCAL_POSE)[-1].pose.position
    assert (p.x, p.y, p.z) == (2.0, 5.0, 3.0)
    assert rig.state().autopilot == "px4" and rig.state().mode == "AUTO.LOITER"


def test_non_finite_telemetry_is_dropped_and_counted():
    rig = CoreRig().connect()
    poses = len(rig.published(registry.LOCAL_POSE))
    rig.now += 0.1
    rig.deliver(mavlink.MAVLink_local_position_ned_message(9000, math.nan, 0, 0, 0, 0, 0))
    assert len(rig.published(registry.LOCAL_POSE)) == poses


def test_bad_setpoints_are_counted_and_change_nothing():
    rig = CoreRig().connect(mode=OFFBOARD, armed=True, flying=True)
    for vx in (math.nan, math.inf, 99.0):
        rig.setpoint(velocity(vx))
    rig.run(0.3)
    assert rig.core.rejected_setpoints == 3
    assert rig.setpoints() == []


def test_commander_lost_lands_once_and_never_re_requests_offboard():
    rig = CoreRig(commander_lost_timeout=2.0).connect(mode=OFFBOARD, armed=True, flying=True)
    rig.run(1.0, stream=True)
    stopped = rig.now
    rig.run(2.5)
    (land,) = rig.commands(NAV_LAND)
    rig.ack(NAV_LAND, ACCEPTED)
    rig.run(2.0)
    assert land.confirmation == 0 and len(rig.commands(NAV_LAND)) == 1
    assert rig.commands(SET_MODE) == []
    states = [s.failsafe for s in rig.published(registry.STATE, since=stopped)]
    assert states.index("hold") < states.index("land")


def test_the_command_lease_refuses_a_non_holder_until_it_takes_over():
    rig = CoreRig(command_lease=True).connect(mode=OFFBOARD, armed=True, flying=True)
    rig.setpoint(velocity(1.0), commander="alice")
    assert rig.state().commander == "alice"
    since, streamed = rig.now, len(rig.setpoints())
    rig.setpoint(velocity(-1.0), commander="bob")
    assert len(rig.setpoints()) == streamed  # not forwarded
    assert rig.core.failsafe.target.velocity.x == 1.0
    refused = {
        ops.arming: CommandBool(value=True),
        ops.takeoff: CommandTOL.takeoff(2.0),
        ops.land: CommandTOL.land(),
        ops.set_mode: SetMode(custom_mode="AUTO.LAND"),
    }
    for steps, request in refused.items():
        op = rig.call(steps, request, commander="bob")
        with pytest.raises(ServiceError, match="'alice' holds the command lease") as error:
            op.result()
        assert error.value.code == "lease", steps.__name__
    assert rig.sent_since(since, "COMMAND_LONG") == []
    assert rig.core.lease.refused_commands == 4 and rig.core.lease.refused_setpoints == 1
    reply = rig.core.on_lease_request(LeaseRequest(action="take_over"), "bob", rig.now, rig.stamp)
    rig._collect()
    assert (reply.granted, reply.previous) == (True, "alice")
    assert rig.state().commander == "bob"
    rig.setpoint(velocity(-1.0), commander="bob")
    assert len(rig.setpoints()) == streamed + 1
    rig.call(ops.arming, CommandBool(value=False), commander="bob")
    assert len(rig.commands(mavlink.MAV_CMD_COMPONENT_ARM_DISARM)) == 1
    rig.setpoint(velocity(1.0), commander="alice")  # alice must take it over in turn
    assert len(rig.setpoints()) == streamed + 1


def test_without_the_command_lease_every_commander_is_obeyed():
    rig = CoreRig().connect(mode=OFFBOARD, armed=True, flying=True)
    rig.setpoint(velocity(1.0), commander="alice")
    rig.setpoint(velocity(-1.0), commander="bob")
    assert len(rig.setpoints()) == 2 and rig.state().commander == ""


def test_ardupilot_guided_while_flying_is_not_pinned_to_its_pose():
    rig = CoreRig(autopilot=ARDUPILOT).connect(mode=ARDU_LOITER, armed=True, flying=True)
    since = rig.now
    op = rig.call(ops.set_mode, SetMode(custom_mode="GUIDED"))
    (sent,) = rig.commands(SET_MODE)
    assert (sent.param1, sent.param2) == (1.0, ARDU_GUIDED)  # no priming: sent at once
    rig.ack(SET_MODE, ACCEPTED)  # ArduPilot acks once: that is the answer
    assert op.result().mode_sent and rig.core.current_state().mode == "GUIDED"
    rig.custom_mode = ARDU_GUIDED
    rig.run(3.5)
    assert rig.setpoints(since=since) == []
    assert rig.core.failsafe.state == "" and not rig.core.failsafe.engaged


def test_ardupilot_has_no_offboard():
    rig = CoreRig(autopilot=ARDUPILOT).connect()
    with pytest.raises(ValueError, match="GUIDED"):
        rig.call(ops.set_mode, SetMode(custom_mode="OFFBOARD")).result()


def test_hold_is_at_the_pose_where_the_velocity_command_expired():
    rig = CoreRig().connect(mode=OFFBOARD, armed=True, flying=True)
    rig.pose(north=1.0, east=1.0, down=-5.0)
    rig.run(1.0, stream=True)
    rig.run(1.0)
    hold = rig.setpoints(mask=MASK_POSITION)[0]
    assert (hold.x, hold.y, hold.z) == (1.0, 1.0, -5.0) and hold.coordinate_frame == 1


@pytest.mark.parametrize(
    ("param", "param_type", "value", "named"),
    [
        ("MPC_XY_VEL_MAX", REAL32, ParamValue(integer=2**64 - 1), "value.integer=1844674407"),
        ("MPC_XY_VEL_MAX", REAL32, ParamValue(real=1e39), "beyond the float32 range"),
        ("COM_RC_IN_MODE", INT32, ParamValue(integer=2**31), "value.integer=2147483648 outside"),
        ("COM_RC_IN_MODE", INT32, ParamValue(real=1.5), "integer parameter"),
    ],
)
def test_param_set_out_of_its_type_is_a_bad_request_and_writes_nothing(
    param, param_type, value, named
):
    rig = CoreRig().connect()
    rig.param(param, 1.0, param_type)  # its type is known
    with pytest.raises(ValueError, match=named) as err:
        rig.call(parameters.param_set, ParamSet(param_id=param, value=value)).result()
    assert param in str(err.value)
    assert rig.sent_since(-math.inf, "PARAM_SET") == []
