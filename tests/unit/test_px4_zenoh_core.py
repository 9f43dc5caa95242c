"""The PX4 Zenoh bridge's core against a recorded PX4 (tests/unit/px4_zenoh_rig.py): what it
presents, what it writes to PX4's ``/fmu/in`` topics, and each bridge rule (version refusal,
lease, late setpoint, validation, envelope, failsafe stream and commander-lost action, link
loss) held by a test."""

from __future__ import annotations

import math

import pytest
from px4_zenoh_rig import (
    NAV_LAND,
    NAV_OFFBOARD,
    NAV_RTL,
    USER,
    Px4Rig,
    velocity,
)
from targets import position
from validation_count import count_validations

from dronewrapper.envelope import Envelope
from dronewrapper.msgs import registry
from dronewrapper.msgs.flight import NOT_READY, TakeoffRequest
from dronewrapper.msgs.lease import LeaseRequest
from dronewrapper.msgs.mavros import LANDED_STATE_ON_GROUND, CommandBool, SetMode
from dronewrapper.msgs.mission import EnvelopeSet
from dronewrapper_bridge_px4_zenoh import commands as cmds
from dronewrapper_bridge_px4_zenoh import envelope_rules, flight
from dronewrapper_bridge_px4_zenoh import operations as ops
from dronewrapper_bridge_px4_zenoh import topics as t
from dronewrapper_bridge_px4_zenoh.versions import Versions


@pytest.fixture
def rig() -> Px4Rig:
    return Px4Rig()


# ---- what it presents


def test_recorded_px4_shows_as_a_connected_landed_disarmed_px4(rig):
    rig.boot()
    state = rig.published(registry.STATE)[-1]
    assert (state.connected, state.armed, state.mode, state.autopilot) == (
        True,
        False,
        "AUTO.LOITER",
        "px4",
    )
    assert rig.published(registry.EXTENDED_STATE)[-1].landed_state == LANDED_STATE_ON_GROUND
    pose = rig.published(registry.LOCAL_POSE)[-1]
    assert pose.header.frame_id == "map" and abs(pose.pose.position.z) < 1.0
    assert rig.published(registry.VELOCITY_BODY)[-1].header.frame_id == "base_link"
    assert rig.published(registry.GLOBAL_POSITION)[-1].latitude == pytest.approx(47.3977, abs=1e-3)
    home = rig.published(registry.HOME_POSITION)[-1]
    assert home.latitude == pytest.approx(47.3977, abs=1e-3) and (home.x, home.y) == (0, 0)
    assert 14.0 < rig.published(registry.BATTERY)[-1].voltage < 17.0


def test_no_sample_for_the_link_timeout_shows_disconnected(rig):
    rig.boot()
    rig.now += 1.5
    rig.tick()
    assert rig.published(registry.STATE)[-1].connected is False
    assert rig.core.require_connected.__self__.connected is False


# ---- versions


def test_a_doctored_token_is_refused_naming_topic_and_both_hashes(rig):
    rig.tokens(doctor="/fmu/out/vehicle_local_position")
    (text,) = [m.text for m in rig.published(registry.STATUSTEXT)]
    expected = Versions().expected["/fmu/out/vehicle_local_position"]
    assert "/fmu/out/vehicle_local_position" in text
    assert expected in text and "RIHS01_" + "ab" * 32 in text


def test_a_sample_in_another_version_is_not_decoded(rig):
    rig.boot()
    rig.clear()
    key = rig.core.versions.key(t.LOCAL_POSITION).rsplit("/", 1)[0] + "/RIHS01_" + "cd" * 32
    rig.send(t.LOCAL_POSITION, key=key, x=5.0)
    assert rig.published(registry.LOCAL_POSE) == []
    assert rig.errors == ["version"]
    assert "RIHS01_" + "cd" * 32 in rig.published(registry.STATUSTEXT)[0].text


def test_nothing_is_written_to_a_topic_px4_reads_in_another_version(rig):
    rig.boot(doctor="/fmu/in/vehicle_command")
    op = rig.request(ops.arming(rig.core, CommandBool(value=True)), "arming")
    rig.run(2.0)
    assert rig.commands() == [] and op.done and "no vehicle_command_ack" in op.reply.message
    assert any("/fmu/in/vehicle_command" in m.text for m in rig.published(registry.STATUSTEXT))


# ---- setpoints


def test_a_body_velocity_is_written_as_offboard_mode_and_a_ned_trajectory(rig):
    rig.flying_offboard()
    rig.clear()
    rig.setpoint(velocity(1.0))
    (mode,) = rig.writes(t.OFFBOARD_MODE)
    assert mode["velocity"] and not mode["position"]
    (sp,) = rig.writes(t.TRAJECTORY)
    assert all(math.isnan(c) for c in sp["position"])
    # forward at the recorded heading (yaw ENU from the attitude): north, east from FLU x
    yaw = rig.core.yaw_enu
    assert sp["velocity"][0] == pytest.approx(math.sin(yaw), abs=1e-5)
    assert sp["velocity"][1] == pytest.approx(math.cos(yaw), abs=1e-5)


def test_a_position_is_written_in_ned(rig):
    rig.flying_offboard()
    rig.clear()
    rig.setpoint(position(1.0, 2.0, 3.0))
    (sp,) = rig.writes(t.TRAJECTORY)
    assert sp["position"] == pytest.approx([2.0, 1.0, -3.0])
    assert rig.writes(t.OFFBOARD_MODE)[0]["position"]


def test_the_lease_refuses_a_setpoint_from_another_commander():
    rig = Px4Rig(command_lease=True)
    rig.flying_offboard()
    rig.core.on_lease_request(LeaseRequest(action="take"), USER, rig.now, rig.stamp)
    rig.clear()
    rig.setpoint(velocity(), commander="intruder")
    assert rig.writes(t.TRAJECTORY) == []
    (refusal,) = rig.published(registry.REFUSAL)
    assert (refusal.kind, refusal.commander) == ("lease", "intruder")


def test_a_late_setpoint_is_refused(rig):
    rig.flying_offboard()
    for _ in range(10):
        rig.setpoint(velocity(), sent=rig.stamp - 0.01)
        rig.now += 0.05
    rig.clear()
    rig.setpoint(velocity(), sent=rig.stamp - 2.0)
    assert rig.writes(t.TRAJECTORY) == []
    assert rig.published(registry.REFUSAL)[0].kind == "late"


def test_an_invalid_setpoint_is_refused(rig):
    rig.flying_offboard()
    rig.clear()
    rig.setpoint(velocity(math.nan))
    assert rig.writes(t.TRAJECTORY) == []
    assert rig.published(registry.REFUSAL)[0].kind == "validation"


def test_a_setpoint_is_validated_once_where_it_enters(rig, monkeypatch):
    calls = count_validations(monkeypatch)
    rig.flying_offboard()
    rig.clear()
    rig.setpoint(velocity(1.0))
    assert len(rig.writes(t.TRAJECTORY)) == 1 and len(calls) == 1


def test_a_setpoint_outside_the_envelope_is_refused():
    rig = Px4Rig(envelope={"max_altitude": 10.0})
    rig.flying_offboard()
    rig.clear()
    rig.setpoint(position(0.0, 0.0, 50.0))
    assert rig.writes(t.TRAJECTORY) == []
    refusal = rig.published(registry.REFUSAL)[0]
    assert (refusal.kind, refusal.limit) == ("envelope", "max_altitude")


# ---- the failsafe


def test_a_stale_velocity_becomes_a_position_hold(rig):
    rig.flying_offboard()
    rig.setpoint(velocity(1.0))
    rig.run(1.0)
    sp = rig.writes(t.TRAJECTORY)[-1]
    assert sp["position"] == pytest.approx([0.0, 0.0, -3.0], abs=1e-3)
    assert rig.published(registry.STATE)[-1].failsafe == "hold"


def test_the_stream_goes_on_at_the_stream_rate(rig):
    rig.flying_offboard()
    rig.setpoint(velocity(1.0))
    rig.clear()
    rig.run(2.0)
    assert len(rig.writes(t.OFFBOARD_MODE)) >= 2.0 * 20  # PX4 leaves OFFBOARD below 2 Hz


def test_a_lost_commander_lands_with_a_vehicle_command(rig):
    rig.flying_offboard()
    rig.setpoint(velocity(1.0))
    rig.run(4.5)
    assert [c for c in rig.commands() if c["command"] == cmds.NAV_LAND] == []
    rig.run(1.0)
    (land,) = [c for c in rig.commands() if c["command"] == cmds.NAV_LAND]
    assert land["from_external"] and land["target_system"] == 1
    rig.ack(cmds.NAV_LAND)
    rig.vehicle(nav_state=NAV_LAND)
    assert rig.published(registry.STATE)[-1].failsafe == "land"


def test_the_bridge_never_fights_the_pilot(rig):
    rig.flying_offboard()
    rig.setpoint(velocity(1.0))
    rig.vehicle(nav_state=2)  # POSCTL: a pilot took over
    assert any("without a request" in m.text for m in rig.published(registry.STATUSTEXT))
    rig.run(1.0)  # the last setpoint goes stale
    rig.clear()
    rig.run(6.0)  # no hold streamed, no landing asked, no OFFBOARD asked again
    assert rig.commands() == [] and rig.writes(t.TRAJECTORY) == []


# ---- commands


def test_arming_is_answered_by_pxs_ack(rig):
    rig.boot()
    rig.clear()
    op = rig.request(ops.arming(rig.core, CommandBool(value=True)), "arming")
    (command,) = rig.commands()
    assert (command["command"], command["param1"]) == (cmds.ARM_DISARM, 1.0)
    rig.ack(cmds.ARM_DISARM)
    assert op.done and op.reply.success and op.reply.message == "ARM_DISARM accepted"


def test_a_refused_command_says_so(rig):
    rig.boot()
    op = rig.request(ops.arming(rig.core, CommandBool(value=True)), "arming")
    rig.ack(cmds.ARM_DISARM, cmds.DENIED)
    assert op.done and not op.reply.success and "denied" in op.reply.message


def test_an_unanswered_command_is_written_again_then_fails(rig):
    rig.boot()
    op = rig.request(ops.arming(rig.core, CommandBool(value=True)), "arming")
    rig.run(2.0)
    assert len(rig.commands()) == 3 and op.done and not op.reply.success


def test_offboard_is_asked_for_only_after_priming(rig):
    rig.boot()
    rig.clear()
    op = rig.request(ops.set_mode(rig.core, SetMode(custom_mode="OFFBOARD")), "set_mode")
    rig.run(1.0)
    assert rig.commands() == [] and len(rig.writes(t.TRAJECTORY)) > 20  # a hold streamed
    rig.run(0.4)
    (command,) = rig.commands()
    assert (command["command"], command["param1"]) == (cmds.SET_NAV_STATE, NAV_OFFBOARD)
    rig.ack(cmds.SET_NAV_STATE)
    rig.vehicle(nav_state=NAV_OFFBOARD)
    assert op.done and op.reply.mode_sent


def test_a_command_from_another_commander_is_refused_by_the_lease():
    rig = Px4Rig(command_lease=True)
    rig.boot()
    rig.core.on_lease_request(LeaseRequest(action="take"), USER, rig.now, rig.stamp)
    op = rig.command(registry.ARMING, ops.arming(rig.core, CommandBool(value=True)), "intruder")
    assert op.done and op.error is not None and rig.commands() == []


# ---- flights


def test_a_takeoff_primes_enters_offboard_arms_and_holds_the_height(rig):
    rig.boot()
    op = rig.request(flight.takeoff_to(rig.core, TakeoffRequest(height=2.5)), "takeoff")
    rig.run(1.5)
    assert [c["command"] for c in rig.commands()] == [cmds.SET_NAV_STATE]
    rig.ack(cmds.SET_NAV_STATE)
    rig.vehicle(nav_state=NAV_OFFBOARD)
    assert [c["command"] for c in rig.commands()][-1] == cmds.ARM_DISARM
    rig.ack(cmds.ARM_DISARM)
    rig.vehicle(armed=True, landed=False)
    rig.run(0.2)
    z0 = rig.core.position_enu[2]
    assert rig.writes(t.TRAJECTORY)[-1]["position"][2] == pytest.approx(-(z0 + 2.5), abs=1e-3)
    rig.at(0.0, 0.0, z0 + 2.45)
    rig.run(0.1)
    assert op.done and op.reply.success, op.reply


def test_a_takeoff_waits_for_pxs_preflight_checks(rig):
    rig.boot()
    rig.send(t.VEHICLE_STATUS, pre_flight_checks_pass=False)
    op = rig.request(flight.takeoff_to(rig.core, TakeoffRequest(height=2.5)), "takeoff")
    assert op.done and op.reply.failure == NOT_READY and rig.commands() == []


def test_the_envelope_can_be_set_and_then_refuses_by_it(rig):
    rig.flying_offboard()
    request = EnvelopeSet(envelope=Envelope(max_altitude=5.0))
    op = rig.request(envelope_rules.set_envelope(rig.core, request), "envelope")
    assert op.done and op.reply.envelope.max_altitude == 5.0 and op.reply.set_by == USER
    rig.clear()
    rig.setpoint(position(0.0, 0.0, 8.0))
    assert rig.writes(t.TRAJECTORY) == []
    assert rig.published(registry.REFUSAL)[0].limit == "max_altitude"


def test_a_command_whose_effect_vehicle_status_shows_needs_no_ack(rig):
    rig.boot()
    op = rig.request(ops.arming(rig.core, CommandBool(value=True)), "arming")
    rig.vehicle(armed=True)  # no ack: PX4's module published another in its place
    assert op.done and op.reply.success and "vehicle_status shows it" in op.reply.message
    assert len(rig.commands()) == 1


def test_a_breach_is_reported_and_its_action_asked_of_px4():
    rig = Px4Rig(envelope={"max_altitude": 10.0, "breach_action": "land"})
    rig.flying_offboard()
    rig.setpoint(velocity(0.5))
    rig.clear()
    rig.at(0.0, 0.0, 12.0)
    rig.tick()
    (refusal,) = rig.published(registry.REFUSAL)
    assert (refusal.kind, refusal.limit, refusal.action) == ("breach", "max_altitude", "land")
    assert [c["command"] for c in rig.commands()] == [cmds.NAV_LAND]
    assert rig.published(registry.STATE)[-1].failsafe == "breach:land"


def test_a_status_older_than_an_accepted_mode_does_not_bring_offboard_back(rig):
    rig.flying_offboard()
    rig.setpoint(velocity(0.5))
    op = rig.request(ops.failsafe_action(rig.core, "return"), "")
    rig.ack(cmds.NAV_RETURN_TO_LAUNCH)
    assert op.done and rig.published(registry.STATE)[-1].mode == "AUTO.RTL"
    rig.run(1.0, status_every=0.25)  # PX4's status still shows OFFBOARD (sent before the ack)
    rig.clear()
    rig.run(0.3, status_every=1.0)
    assert rig.core.heartbeat_state.mode == "AUTO.RTL"
    assert rig.writes(t.TRAJECTORY) == []  # no stream: PX4 stays in its return
    rig.vehicle(nav_state=NAV_RTL)
    rig.run(1.0)
    assert rig.core.heartbeat_state.mode == "AUTO.RTL" and rig.writes(t.TRAJECTORY) == []


def test_a_status_px4_stamped_before_the_ack_is_kept_out_whenever_it_arrives(rig):
    rig.flying_offboard()
    rig.send(t.VEHICLE_STATUS, timestamp=10_000_000)
    rig.setpoint(velocity(0.5))
    op = rig.request(ops.failsafe_action(rig.core, "return"), "")
    rig.send(t.COMMAND_ACK, command=cmds.NAV_RETURN_TO_LAUNCH, result=0, timestamp=11_000_000)
    assert op.done and rig.core.heartbeat_state.mode == "AUTO.RTL"
    rig.now += 2.0  # past ENTERED_HOLD_S: a status held on the way arrives late
    rig.send(t.VEHICLE_STATUS, timestamp=10_900_000)  # still OFFBOARD, stamped before the ack
    assert rig.core.heartbeat_state.mode == "AUTO.RTL"
    rig.send(t.VEHICLE_STATUS, timestamp=12_000_000)  # after the ack: PX4 is in OFFBOARD again
    assert rig.core.heartbeat_state.mode == "OFFBOARD"
