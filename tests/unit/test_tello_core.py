"""bridge_tello's contract rules, one test each, on the pure core with real Tello SDK strings.

The rig (tello_core_rig.py) moves time itself and plays the Tello: state strings at 10 Hz,
replies from a script. What the core sends is exactly what the Tello's port 8889 would get.
"""

from __future__ import annotations

import itertools

import pytest
from targets import velocity
from tello_core_rig import TelloRig

from dronewrapper.msgs import mavros, registry
from dronewrapper.msgs.lease import LeaseRequest
from dronewrapper.runtime import ServiceError
from dronewrapper_bridge_tello import operations as ops

STOP = (0, 0, 0, 0)


def flying_rig(**config) -> TelloRig:
    rig = TelloRig(**config)
    rig.connect()
    assert rig.call(ops.takeoff, mavros.CommandTOL.takeoff()).success
    assert rig.core.telemetry.landed.state == mavros.LANDED_STATE_IN_AIR
    return rig


def test_connects_with_command_then_streamon():
    rig = TelloRig(video=True)
    rig.connect()
    rig.run(0.5)
    assert rig.commands()[:2] == ["command", "streamon"]
    assert rig.core.streaming
    state = rig.published(registry.STATE)[-1]
    assert state.connected and state.guided and state.mode == "SDK"


def test_fresh_setpoint_flies_rc_signed_and_scaled_at_20_hz():
    rig = flying_rig()
    start = rig.now
    # forward 0.3, left 0.2, up 0.1 m/s, CCW 0.4 rad/s -> a -20 (left), b 30, c 10, d -23 (CCW)
    rig.stream(velocity(0.3, 0.2, 0.1, 0.4), 1.0)
    flown = [s for t, s in rig.rcs(start + 0.1)]
    assert flown and set(flown) == {(-20, 30, 10, -23)}
    assert len(rig.rcs(start)) >= 20  # >= rc_rate_hz while commanded
    assert rig.sent[-1][1] == "rc -20 30 10 -23"  # the SDK's text, as the Tello parses it


def test_rc_values_are_clamped_to_max_stick():
    rig = flying_rig()
    start = rig.now
    rig.stream(velocity(2.5, 0.0, 1.5, -3.0), 0.3)  # within the setpoint limits, beyond 100
    assert {s for _, s in rig.rcs(start + 0.1)} == {(0, 100, 100, 100)}
    start = rig.now
    rig.stream(velocity(0.0, 2.5, -1.5, 3.0), 0.3)
    assert {s for _, s in rig.rcs(start + 0.1)} == {(-100, 0, -100, -100)}
    rig.stream(velocity(5.0), 0.3)  # beyond max_horizontal_speed: refused, not flown
    assert rig.core.rejected_setpoints > 0


def test_stale_setpoint_sends_a_real_stop_repeated_then_holds():
    rig = flying_rig()
    rig.stream(velocity(0.5), 0.5)
    stopped = rig.now
    rig.run(1.5)
    after = rig.rcs(stopped + 0.5 + 0.06)  # past setpoint_timeout: no more flying sticks
    stops = [t for t, s in after if s == STOP]
    assert after and all(s == STOP for _, s in after)
    assert stops[0] - stopped < 0.5 + 0.1  # the stop follows the expiry at once ...
    assert len(stops) >= 5  # ... repeated (UDP may lose one): 0.5 s at 20 Hz
    assert rig.core.failsafe.state == "hold"
    texts = [m.text for m in rig.published(registry.STATUSTEXT)]
    assert any("failsafe hold" in t for t in texts)


def test_commander_lost_lands_once():
    rig = flying_rig()
    rig.stream(velocity(0.5), 0.5)
    lost_at = rig.now
    rig.run(4.0)
    assert "land" not in rig.commands(lost_at)
    rig.delays["land"] = 3.0  # the Tello answers once on the ground
    rig.run(2.0)
    assert rig.commands(lost_at).count("land") == 1
    assert rig.core.failsafe.state == "land"
    rig.run(4.0)
    assert rig.core.failsafe.state == "" and not rig.flying  # landed: the state clears
    rig.run(6.0)
    assert rig.commands(lost_at).count("land") == 1


def test_commander_lost_hold_keeps_hovering():
    rig = flying_rig(commander_lost_action="hold")
    rig.stream(velocity(0.5), 0.5)
    rig.run(8.0)
    assert "land" not in rig.commands() and rig.flying
    assert rig.core.failsafe.state == "hold"


def test_no_sticks_on_the_ground_even_for_a_streaming_commander():
    rig = TelloRig()
    rig.connect()
    rig.stream(velocity(0.5, vz=0.3), 2.0)  # fresh setpoints all along
    rig.run(1.0)  # then stale: no stop either
    assert rig.core.failsafe.target is not None and rig.rcs() == []
    assert rig.core.telemetry.landed.state == mavros.LANDED_STATE_ON_GROUND


def test_keepalive_while_flying_and_nothing_on_the_ground():
    rig = TelloRig()
    rig.connect()
    rig.run(8.0)
    assert rig.rcs() == []  # on the ground: no sticks, no keep-alive
    assert rig.call(ops.takeoff, mavros.CommandTOL.takeoff()).success
    flying_since = rig.now
    rig.run(10.0)  # nobody steers: the bridge keeps the Tello alive, never lands it
    stops = [t for t, s in rig.rcs(flying_since) if s == STOP]
    gaps = [b - a for a, b in zip([flying_since, *stops], stops, strict=False)]
    assert len(stops) >= 3 and max(gaps) <= 3.0 + 0.1  # keepalive_s, well under 15 s
    assert "land" not in rig.commands(flying_since)


def test_no_sticks_while_taking_off_or_landing():
    rig = TelloRig()
    rig.connect()
    rig.delays["takeoff"] = 2.0
    op = rig.start(ops.takeoff, mavros.CommandTOL.takeoff())
    rig.stream(velocity(0.5), 1.5)  # a commander streams during the take-off
    assert not op.done and rig.rcs() == []
    rig.run(1.0)
    assert op.done and op.result().success


def test_takeoff_while_flying_does_nothing():
    rig = flying_rig()
    since = rig.now
    reply = rig.call(ops.takeoff, mavros.CommandTOL.takeoff(altitude=5.0))
    assert reply.success and reply.message == "already flying"
    assert rig.commands(since) == []


def test_takeoff_refusal_carries_the_tellos_text():
    rig = TelloRig()
    rig.connect()
    rig.script["takeoff"] = "error No valid imu"
    reply = rig.call(ops.takeoff, mavros.CommandTOL.takeoff())
    assert not reply.success and reply.result == 2 and "error No valid imu" in reply.message
    assert not rig.core.telemetry.landed.flying
    assert rig.commands().count("takeoff") == 1  # sent once, never retried


def test_takeoff_whose_ok_was_lost_is_confirmed_by_the_height():
    rig = TelloRig(takeoff_timeout=3.0)
    rig.connect()
    rig.script["takeoff"] = None  # it takes off, but the ok is lost
    rig.flying, rig.height_cm = True, 100
    reply = rig.call(ops.takeoff, mavros.CommandTOL.takeoff())
    assert reply.success and "reply lost" in reply.message


def test_takeoff_to_an_altitude_moves_up_after_the_ok():
    rig = TelloRig()
    rig.connect()
    reply = rig.call(ops.takeoff, mavros.CommandTOL.takeoff(altitude=2.0))
    assert reply.success and rig.commands()[-2:] == ["takeoff", "up 100"]


def test_a_command_without_reply_is_retried_then_reported():
    rig = TelloRig(command_timeout=0.3)
    rig.connect()
    rig.script["speed?"] = None
    since = rig.now
    reply = rig.call(ops.param_get, mavros.ParamGet(param_id="SPEED"))
    assert not reply.success and "no reply" in reply.message
    asked = [t for t, c in rig.sent if c == "speed?" and t >= since]
    assert len(asked) == 3  # command_attempts
    assert all(b - a >= 0.3 - 1e-9 for a, b in itertools.pairwise(asked))
    reply = rig.call(ops.param_get, mavros.ParamGet(param_id="BATTERY"))
    assert reply.success and reply.value.real == 80.0


def test_replies_are_matched_to_their_command():
    """A late ok of a retried command is not taken for the next command's answer, and a value
    never answers a command that is not a read."""
    rig = TelloRig(command_timeout=0.3)
    rig.connect()
    rig.script["speed 50"] = None  # both sends' oks come late, by hand
    first = rig.start(ops.param_set, mavros.ParamSet.of("SPEED", 50))
    rig.run(0.35)
    assert rig.commands().count("speed 50") == 2
    rig.reply_now("ok")  # the first send's ok, after the retry
    rig.delays["battery?"] = 0.3  # the next command's answer comes after the stray ok
    second = rig.start(ops.param_get, mavros.ParamGet(param_id="BATTERY"))
    rig.run(0.1)
    rig.reply_now("ok")  # the second send's ok: still speed 50's, not battery?'s
    rig.run(1.0, until=lambda: second.done)
    assert first.result().success
    reply = second.result()
    assert reply.success and reply.value.real == 80.0 and reply.message == "80"
    rig.script["speed 60"] = None
    op = rig.start(ops.param_set, mavros.ParamSet.of("SPEED", 60))
    rig.reply_now("87")  # a value cannot answer "speed 60": that slot's reply was lost
    assert not op.done and rig.core.matcher.lost == 1
    rig.run(0.35)
    rig.reply_now("ok")  # the retry's answer
    rig.run(1.0, until=lambda: op.done)
    assert op.result().success and rig.commands().count("speed 60") == 2


def test_one_command_in_flight_at_a_time():
    rig = TelloRig()
    rig.connect()
    rig.delays["speed?"] = 0.5
    first = rig.start(ops.param_get, mavros.ParamGet(param_id="SPEED"))
    second = rig.start(ops.param_get, mavros.ParamGet(param_id="BATTERY"))
    assert rig.commands()[-1] == "speed?"  # battery? waits for speed?'s reply
    rig.run(2.0, until=lambda: second.done)
    assert first.result().value.real == 100.0 and second.result().value.real == 80.0
    assert rig.commands()[-2:] == ["speed?", "battery?"]


def test_modes_map_to_tello_commands():
    rig = flying_rig()
    with pytest.raises(ValueError, match="valid: OFFBOARD"):
        rig.call(ops.set_mode, mavros.SetMode(custom_mode="STABILIZED"))
    assert rig.call(ops.set_mode, mavros.SetMode(custom_mode="AUTO.LOITER")).mode_sent
    assert rig.call(ops.set_mode, mavros.SetMode(custom_mode="OFFBOARD")).mode_sent
    assert rig.commands()[-2:] == ["stop", "command"]
    assert rig.call(ops.set_mode, mavros.SetMode(custom_mode="AUTO.LAND")).mode_sent
    assert rig.commands()[-1] == "land" and not rig.flying


def test_arming_and_parameters_are_mapped_honestly():
    rig = flying_rig()
    reply = rig.call(ops.arming, mavros.CommandBool(value=False))
    assert not reply.success and "cannot disarm" in reply.message
    rig.script["speed 50"] = "out of range"
    reply = rig.call(ops.param_set, mavros.ParamSet.of("SPEED", 50))
    assert not reply.success and "out of range" in reply.message
    with pytest.raises(ValueError, match=r"\[10, 100\]"):
        rig.call(ops.param_set, mavros.ParamSet.of("SPEED", 500))
    reply = rig.call(ops.param_set, mavros.ParamSet.of("BATTERY", 5))
    assert not reply.success and "read-only" in reply.message
    with pytest.raises(ValueError, match="known: SPEED"):
        rig.call(ops.param_get, mavros.ParamGet(param_id="NOPE"))


def test_link_lost_then_reconnected_with_command():
    rig = TelloRig()
    rig.connect()
    rig.streaming_state = False  # the Tello restarts: no state string, no answer
    rig.script["command"] = None
    since = rig.now
    rig.run(4.0)
    assert not rig.core.connected and not rig.core.sdk_mode
    assert rig.commands(since).count("command") >= 2  # asked every reconnect_s
    with pytest.raises(ServiceError, match="not connected"):
        rig.call(ops.land, mavros.CommandTOL.land())
    since = rig.now
    rig.streaming_state = True
    del rig.script["command"]
    rig.connect()
    assert "command" in rig.commands(since)


def test_land_on_the_ground_sends_nothing():
    rig = TelloRig()
    rig.connect()
    assert rig.core.telemetry.landed.state == mavros.LANDED_STATE_ON_GROUND
    reply = rig.call(ops.land, mavros.CommandTOL.land())
    assert reply.success and reply.message == "already on the ground"
    assert rig.commands() == ["command"]


def test_the_command_lease_refuses_a_non_holder_until_it_takes_over():
    rig = flying_rig(command_lease=True)  # the rig's commander took off: it holds the lease
    holder = rig.core.commander
    assert holder and rig.published(registry.STATE)[-1].commander == holder
    since = rig.now
    rig.setpoint(velocity(0.5), commander="bob")
    rig.run(0.3)
    assert {sticks for _, sticks in rig.rcs(since)} <= {STOP}  # bob's sticks never flown
    for steps, request in (
        (ops.arming, mavros.CommandBool(value=True)),
        (ops.takeoff, mavros.CommandTOL.takeoff(2.0)),
        (ops.land, mavros.CommandTOL.land()),
        (ops.set_mode, mavros.SetMode(custom_mode="AUTO.LAND")),
    ):
        with pytest.raises(ServiceError, match="holds the command lease") as error:
            rig.call(steps, request, commander="bob")
        assert error.value.code == "lease", steps.__name__
    assert rig.commands(since) == [] and rig.flying
    reply = rig.core.on_lease_request(LeaseRequest(action="take_over"), "bob", rig.now, rig.now)
    rig.collect()
    assert (reply.granted, reply.previous) == (True, holder)
    assert rig.published(registry.STATE)[-1].commander == "bob"
    taken = rig.now
    rig.stream(velocity(0.5), 0.3, commander="bob")
    assert any(sticks[1] > 0 for _, sticks in rig.rcs(taken))  # forward: pitch stick
    rig.setpoint(velocity(-0.5), commander=holder)  # refused in turn
    assert rig.core.failsafe.target.velocity.x == 0.5


def test_state_shows_a_lapsed_lease_and_malformed_states_are_counted():
    rig = TelloRig(command_lease=True, command_lease_ttl_s=2.0)
    rig.connect()
    rig.setpoint(velocity(), commander="alice")
    rig.run(0.2)
    assert rig.published(registry.STATE)[-1].commander == "alice"
    rig.run(2.0)  # alice silent for the ttl: State says nobody holds it
    assert rig.published(registry.STATE)[-1].commander == ""
    rig.core.on_state(b"pitch:nan;", rig.now, rig.now)
    assert rig.core.malformed_states == 1 and rig.core.connected
