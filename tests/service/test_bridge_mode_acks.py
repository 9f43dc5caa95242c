"""Mode changes as real PX4 answers them (issue 12, items 1-3), bridge in-process over real UDP.

The scripted PX4 of test_bridge_node.py acknowledges DO_SET_MODE twice like the real one: its
MAVLink receiver's ACCEPTED at once, then the commander's result (a refusal with STATUSTEXT for
a mode it cannot enter). The SDK runs against the bridge where the rule is about what a caller
of ``set_mode()`` / ``takeoff()`` sees.
"""

from __future__ import annotations

import time

import pytest
from test_bridge_node import (  # the scripted autopilot and its rig
    AUTO_LAND,
    AUTO_LOITER,
    OFFBOARD,
    make_rig,
    stream,
    velocity,
)

from dronewrapper import CommandRefused, DroneWrapper
from dronewrapper.msgs import registry
from dronewrapper.msgs.mavros import MASK_POSITION, CommandBool, CommandTOL, SetMode
from support import wait_for

REFUSED_TEXT = "Switching to Offboard is currently not available"


@pytest.fixture
def rig(router):
    yield from make_rig(router, autopilot=12)


def flying_offboard(bridge, fake) -> None:
    fake.custom_mode, fake.armed, fake.landed_state = OFFBOARD, True, 2
    fake.position_ned = (1.0, 1.0, -3.0)
    wait_for(lambda: bridge.failsafe.mode == "OFFBOARD" and bridge.failsafe.airborne, 10)


def test_refused_mode_reaches_the_caller_with_px4s_reason(rig):
    """ACCEPTED, then TEMPORARILY_REJECTED: set_mode must not report success."""
    bridge, fake, user = rig
    flying_offboard(bridge, fake)
    for mode, name in (("POSCTL", "Position"), ("ALTCTL", "Altitude")):
        reply = user.call(registry.SET_MODE, SetMode(custom_mode=mode), timeout=15)
        assert not reply.mode_sent and reply.result == 1, reply
        assert "TEMPORARILY_REJECTED" in reply.message
        assert f"Switching to {name} is currently not available" in reply.message
        assert fake.custom_mode == OFFBOARD and bridge.current_state().mode == "OFFBOARD"


def test_refused_mode_reaches_sdk_set_mode(rig, router):
    bridge, fake, _user = rig
    flying_offboard(bridge, fake)
    with DroneWrapper("drone", router, timeout=20, cameras=()) as drone:
        with pytest.raises(CommandRefused, match="Switching to Position is currently not"):
            drone.set_mode("POSCTL")
        assert drone.get_state().mode == "OFFBOARD"


def test_takeoff_does_not_arm_before_px4_really_accepts_offboard(rig, router):
    """The commander's refusal (second ack) stops take-off before any arming command."""
    _bridge, fake, _user = rig
    fake.refuse_modes[OFFBOARD] = REFUSED_TEXT
    drone = DroneWrapper("drone", router, timeout=20, cameras=())
    with drone, pytest.raises(CommandRefused, match=REFUSED_TEXT):
        drone.takeoff(h=2.0, timeout=20)
    assert fake.commands_named(176) and not fake.commands_named(400)
    assert not fake.armed and fake.custom_mode == AUTO_LOITER


def test_mode_acked_once_is_confirmed_by_heartbeat_or_refused(rig):
    """An autopilot that acks DO_SET_MODE only once: the mode must show in HEARTBEAT."""
    bridge, fake, user = rig
    fake.mode_acks = 1
    reply = user.call(registry.SET_MODE, SetMode(custom_mode="AUTO.LAND"), timeout=15)
    assert reply.mode_sent and "confirmed by HEARTBEAT" in reply.message, reply
    fake.mode_changes = False  # ACCEPTED, but it stays in AUTO.LAND
    reply = user.call(registry.SET_MODE, SetMode(custom_mode="AUTO.LOITER"), timeout=15)
    assert not reply.mode_sent and "still in AUTO.LAND" in reply.message, reply
    assert fake.custom_mode == AUTO_LAND and bridge.config.mode_confirm_timeout == 2.5


def test_land_is_known_from_its_ack_no_spurious_hold(rig):
    """Issue 12.3: with PX4's 1 Hz heartbeat the bridge learnt AUTO.LAND up to 1 s late, and
    the setpoints stopped by land() expired meanwhile: 'failsafe: hold' on 7 of 8 landings."""
    bridge, fake, user = rig
    fake.heartbeat_every = 50  # 1 Hz, like PX4
    flying_offboard(bridge, fake)
    states: list = []
    user.subscribe(registry.STATE, states.append)
    pub = user.publisher(registry.SETPOINT_RAW_LOCAL)
    for _ in range(3):  # each landing right after the SDK's stream stops, as land() does
        stream(pub, velocity(vx=0.5), 0.6)
        since = len(states)
        reply = user.call(registry.LAND, CommandTOL.land(), timeout=15)
        answered = time.monotonic()
        assert reply.success, reply
        wait_for(lambda: "AUTO.LAND" in modes_after(states, since), 5, what="AUTO.LAND")  # noqa: B023
        known_after = time.monotonic() - answered
        time.sleep(1.5)  # past setpoint_timeout (0.5 s) and the next heartbeat
        assert all(s.failsafe == "" for s in states[since:]), [s.failsafe for s in states]
        assert known_after < 0.5, f"AUTO.LAND published {known_after:.2f} s after the ack"
        assert not bridge.link.setpoints(MASK_POSITION), "a hold was streamed"
        fake.custom_mode = OFFBOARD  # back in OFFBOARD for the next landing
        wait_for(lambda: bridge.failsafe.mode == "OFFBOARD", 5)


def modes_after(states: list, since: int) -> list[str]:
    return [s.mode for s in states[since:]]


def test_guided_mode_re_entered_by_a_ground_station_applies_the_contract_again(rig):
    """Issue 12.2: AUTO.LOITER and back to OFFBOARD by a GCS, the app keeps streaming, then
    dies: the bridge holds, then lands (before the fix, PX4's own failsafe flew RTL)."""
    bridge, fake, user = rig
    flying_offboard(bridge, fake)
    texts: list[str] = []
    user.subscribe(registry.STATUSTEXT, lambda t: texts.append(t.text))
    pub = user.publisher(registry.SETPOINT_RAW_LOCAL)
    stream(pub, velocity(vx=0.5), 0.5)
    fake.custom_mode = AUTO_LOITER  # the ground station
    wait_for(lambda: any("not switching back" in t for t in texts), 10, what="takeover seen")
    stream(pub, velocity(vx=0.5), 0.5)
    fake.custom_mode = OFFBOARD  # the ground station hands it back
    wait_for(lambda: bridge.failsafe.mode == "OFFBOARD", 10)
    last = stream(pub, velocity(vx=0.5), 0.5)  # the app's last setpoints, then it dies
    assert bridge.failsafe.engaged and not bridge.failsafe.pilot_override
    wait_for(lambda: bridge.failsafe.state == "hold", 5, what="hold")
    land = wait_for(lambda: fake.commands_named(21), 10, what="NAV_LAND")
    assert land[0].confirmation == 0
    landed_at = bridge.link.command_times(21)[0]
    lost_for = landed_at - last
    assert 1.5 < lost_for < 5.0, f"NAV_LAND {lost_for:.2f} s after the last setpoint"  # 2 s
    assert not fake.commands_named(176)  # never asked for OFFBOARD itself


def test_arming_still_acked_once(rig):
    _bridge, fake, user = rig
    assert user.call(registry.ARMING, CommandBool(value=True), timeout=10).success
    assert fake.armed


def test_set_mode_replies_after_the_commanders_ack_so_arming_comes_after_it(rig):
    """A slow commander (0.4 s between the acks): set_mode must not return on the first one,
    so the SDK's arm() (sent after set_mode returns) can never precede PX4's real answer."""
    _bridge, fake, user = rig
    fake.commander_delay = 0.4
    reply = user.call(registry.SET_MODE, SetMode(custom_mode="OFFBOARD"), timeout=15)
    assert reply.mode_sent and reply.result == 0, reply
    assert user.call(registry.ARMING, CommandBool(value=True), timeout=10).success
    (commander_ack,) = fake.commander_acks
    arm_received = min(t for t, m in list(fake.commands) if m.command == 400)
    assert arm_received > commander_ack
