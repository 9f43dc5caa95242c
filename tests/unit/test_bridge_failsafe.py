"""The failsafe contract as a state machine with injected time."""

from __future__ import annotations

import pytest
from targets import velocity

from dronewrapper.msgs.mavros import (
    LANDED_STATE_IN_AIR,
    LANDED_STATE_ON_GROUND,
    MASK_POSITION,
    MASK_VELOCITY,
)
from dronewrapper_bridge_base.guided_failsafe import Failsafe, FailsafeConfig, is_airborne
from dronewrapper_bridge_mavlink.setpoints import Kind, hold_target

POSE = ((1.0, 2.0, 5.0), 0.3)


def flying(fs: Failsafe, now=0.0, mode="OFFBOARD"):
    fs.on_vehicle(mode=mode, armed=True, airborne=True, now=now)
    return fs


def test_fresh_velocity_forwarded_then_hold_at_current_pose_after_timeout():
    fs = flying(Failsafe())
    fs.on_setpoint(velocity(), Kind.VELOCITY, 1.0)
    tick = fs.tick(1.4, POSE)
    assert tick.send.type_mask == MASK_VELOCITY and fs.state == ""
    tick = fs.tick(1.51, POSE)
    assert tick.send.type_mask == MASK_POSITION
    p = tick.send.position
    assert (p.x, p.y, p.z, tick.send.yaw) == (1.0, 2.0, 5.0, 0.3)
    assert fs.state == "hold"
    assert [(t.old, t.new) for t in tick.transitions] == [("", "hold")]
    # the hold point is latched: later pose changes do not drag it
    later = fs.tick(2.0, ((9.0, 9.0, 9.0), 0.0))
    assert later.send.position.x == 1.0 and later.transitions == []


def test_fresh_setpoint_leaves_hold():
    fs = flying(Failsafe())
    fs.on_setpoint(velocity(), Kind.VELOCITY, 0.0)
    fs.tick(1.0, POSE)
    fs.on_setpoint(velocity(0.5), Kind.VELOCITY, 1.2)
    tick = fs.tick(1.25, POSE)
    assert fs.state == "" and tick.send.velocity.x == 0.5
    assert [(t.old, t.new) for t in tick.transitions] == [("hold", "")]


def test_stale_position_target_holds_the_target_not_the_pose():
    fs = flying(Failsafe())
    target = hold_target((10.0, 0.0, 3.0), 0.0)
    fs.on_setpoint(target, Kind.POSITION, 0.0)
    tick = fs.tick(1.0, POSE)
    assert tick.send.position.x == 10.0 and fs.state == "hold"


def test_commander_lost_lands_once_while_airborne():
    fs = flying(Failsafe())
    fs.on_setpoint(velocity(), Kind.VELOCITY, 0.0)
    assert fs.tick(4.9, POSE).request is None
    tick = fs.tick(5.1, POSE)
    assert tick.request == "land" and fs.state == "land"
    assert [(t.old, t.new) for t in tick.transitions] == [("hold", "land")]
    assert fs.tick(5.2, POSE).request is None  # asked once
    # the autopilot switches to AUTO.LAND as asked: expected, no event, bridge stops streaming
    fs.on_mode_requested("AUTO.LAND", 5.15)
    fs.on_vehicle(mode="AUTO.LAND", armed=True, airborne=True, now=5.5)
    tick = fs.tick(5.6, POSE)
    assert tick.send is None and tick.events == [] and fs.state == "land"
    fs.on_vehicle(mode="AUTO.LAND", armed=False, airborne=False, now=20.0)
    assert fs.state == ""  # landed and disarmed: failsafe over


@pytest.mark.parametrize("action", ["return", "hold"])
def test_commander_lost_action_configurable(action):
    fs = flying(Failsafe(FailsafeConfig(commander_lost_action=action)))
    fs.on_setpoint(velocity(), Kind.VELOCITY, 0.0)
    tick = fs.tick(6.0, POSE)
    if action == "hold":
        assert tick.request is None and fs.state == "hold" and tick.send is not None
    else:
        assert tick.request == "return" and fs.state == "return"


def test_no_land_on_the_ground():
    fs = Failsafe()
    fs.on_vehicle(mode="OFFBOARD", armed=True, airborne=False, now=0.0)
    fs.on_setpoint(velocity(), Kind.VELOCITY, 0.0)
    assert fs.tick(10.0, POSE).request is None


def test_pilot_takeover_is_reported_and_not_fought():
    fs = flying(Failsafe())
    fs.on_setpoint(velocity(), Kind.VELOCITY, 0.0)
    fs.tick(1.0, POSE)  # hold
    fs.on_vehicle(mode="POSCTL", armed=True, airborne=True, now=1.5)
    tick = fs.tick(1.6, POSE)
    assert len(tick.events) == 1 and "OFFBOARD" in tick.events[0] and "POSCTL" in tick.events[0]
    assert tick.send is None and fs.state == ""  # stops its own hold stream
    assert fs.pilot_override
    # commander silence long after: still no land request, no stream, no mode request
    for t in (6.0, 10.0, 30.0):
        tick = fs.tick(t, POSE)
        assert tick.request is None and tick.send is None


def test_pilot_override_cleared_when_guided_mode_requested_again():
    fs = flying(Failsafe())
    fs.on_vehicle(mode="POSCTL", armed=True, airborne=True, now=1.0)
    fs.on_mode_requested("OFFBOARD", 2.0)
    assert not fs.pilot_override


def test_fresh_commands_still_forwarded_after_takeover():
    """Forwarding is harmless outside OFFBOARD and keeps a later OFFBOARD request primed."""
    fs = flying(Failsafe(), mode="POSCTL")
    fs.on_setpoint(velocity(), Kind.VELOCITY, 0.0)
    assert fs.tick(0.1, POSE).send is not None


def test_priming_streams_a_hold_without_setpoints():
    fs = Failsafe()
    fs.on_vehicle(mode="AUTO.LOITER", armed=False, airborne=False, now=0.0)
    assert fs.tick(0.0, POSE).send is None
    fs.start_priming(0.0, 1.5)
    tick = fs.tick(0.5, POSE)
    assert tick.send.type_mask == MASK_POSITION and tick.send.position.z == 5.0
    assert fs.tick(1.6, POSE).send is None


def test_mode_requested_by_bridge_is_not_a_takeover():
    fs = flying(Failsafe())
    fs.on_mode_requested("AUTO.LAND", 1.0)
    fs.on_vehicle(mode="AUTO.LAND", armed=True, airborne=True, now=1.5)
    assert fs.tick(1.6, POSE).events == [] and not fs.pilot_override


def test_is_airborne():
    assert is_airborne(LANDED_STATE_IN_AIR, False)
    assert not is_airborne(LANDED_STATE_ON_GROUND, True)
    assert is_airborne(0, True) and not is_airborne(0, False)


def test_bad_config_refused():
    with pytest.raises(ValueError, match="commander_lost_action"):
        FailsafeConfig(commander_lost_action="panic")
    with pytest.raises(ValueError):
        FailsafeConfig(setpoint_timeout=6.0, commander_lost_timeout=5.0)


def test_not_engaged_before_anyone_commands_in_guided_mode():
    """ArduPilot: GUIDED + NAV_TAKEOFF, nobody streaming: no hold at the ground, no land."""
    fs = Failsafe()
    fs.on_vehicle(mode="GUIDED", armed=True, airborne=True, now=0.0)
    fs.on_takeoff_requested(0.0)
    for t in (1.0, 6.0, 20.0):
        tick = fs.tick(t, POSE)
        assert tick.send is None and tick.request is None and fs.state == ""
    fs.on_setpoint(velocity(), Kind.VELOCITY, 21.0)  # a commander steers: engaged from now
    assert fs.engaged
    assert fs.tick(21.6, POSE).send.type_mask == MASK_POSITION and fs.state == "hold"
    assert fs.tick(26.1, POSE).request == "land"


def test_entering_guided_with_a_fresh_stream_engages():
    """PX4: the SDK streams, then OFFBOARD is entered: the bridge is responsible from then."""
    fs = Failsafe()
    fs.on_vehicle(mode="AUTO.LOITER", armed=True, airborne=True, now=0.0)
    fs.on_setpoint(velocity(), Kind.VELOCITY, 0.9)
    assert not fs.engaged
    fs.on_vehicle(mode="OFFBOARD", armed=True, airborne=True, now=1.0)
    assert fs.engaged
    fs.on_vehicle(mode="AUTO.LAND", armed=True, airborne=True, now=2.0)
    assert not fs.engaged


def test_hold_ends_when_a_requested_landing_starts():
    fs = flying(Failsafe())
    fs.on_setpoint(velocity(), Kind.VELOCITY, 0.0)
    fs.tick(0.6, POSE)
    assert fs.state == "hold"
    fs.on_mode_requested("AUTO.LAND", 0.7)
    fs.on_vehicle(mode="AUTO.LAND", armed=True, airborne=True, now=1.0)
    tick = fs.tick(1.1, POSE)
    assert fs.state == "" and tick.send is None and tick.events == []
    assert [(t.old, t.new) for t in tick.transitions] == [("hold", "")]


def test_guided_re_entered_by_someone_else_with_a_live_commander_applies_the_contract():
    """Issue 12.2: a GCS switched OFFBOARD -> AUTO.LOITER -> OFFBOARD while the app kept
    streaming; when the app then dies the bridge must hold, then land (not leave it to PX4's
    own failsafe, which flew RTL)."""
    fs = flying(Failsafe())
    for t in (0.0, 0.5, 1.0):
        fs.on_setpoint(velocity(), Kind.VELOCITY, t)
    fs.on_vehicle(mode="AUTO.LOITER", armed=True, airborne=True, now=1.2)  # the GCS
    assert fs.pilot_override
    fs.on_setpoint(velocity(), Kind.VELOCITY, 1.5)
    fs.on_vehicle(mode="OFFBOARD", armed=True, airborne=True, now=1.8)  # the GCS, back
    assert not fs.pilot_override and fs.engaged  # the app still streams: engaged at once
    fs.on_setpoint(velocity(), Kind.VELOCITY, 2.0)  # the app's last setpoint, then it dies
    tick = fs.tick(2.6, POSE)
    assert fs.state == "hold" and tick.send.type_mask == MASK_POSITION
    assert fs.tick(7.1, POSE).request == "land"


def test_guided_re_entered_with_nobody_streaming_is_left_to_the_autopilot():
    fs = flying(Failsafe())
    fs.on_setpoint(velocity(), Kind.VELOCITY, 0.0)
    fs.on_vehicle(mode="AUTO.LOITER", armed=True, airborne=True, now=1.0)
    fs.on_vehicle(mode="OFFBOARD", armed=True, airborne=True, now=10.0)
    assert not fs.pilot_override and not fs.engaged
    for t in (10.6, 16.0, 30.0):
        tick = fs.tick(t, POSE)
        assert tick.send is None and tick.request is None
    fs.on_setpoint(velocity(), Kind.VELOCITY, 31.0)  # a commander steers again
    assert fs.engaged and fs.tick(36.1, POSE).request == "land"


def test_takeoff_request_ends_priming_no_ground_hold_into_the_climb():
    """Issue 21: no hold at the ground pose may be streamed once a take-off is requested."""
    fs = Failsafe()
    fs.on_vehicle(mode="GUIDED", armed=False, airborne=False, now=0.0)
    fs.start_priming(0.0, 3.0)
    assert fs.tick(0.1, POSE).send is not None
    fs.on_vehicle(mode="GUIDED", armed=True, airborne=False, now=0.15)
    fs.on_takeoff_requested(0.2)
    assert not fs.priming(0.21)
    for t in (0.25, 1.0, 2.9, 12.0):
        assert fs.tick(t, POSE).send is None


def test_confirmed_mode_ends_priming():
    fs = Failsafe()
    fs.on_vehicle(mode="AUTO.LOITER", armed=False, airborne=False, now=0.0)
    fs.start_priming(0.0, 3.2)
    fs.on_vehicle(mode="OFFBOARD", armed=False, airborne=False, now=1.3)
    fs.end_priming(1.3, engage=False)
    assert not fs.priming(1.31) and fs.tick(1.4, POSE).send is None


def test_primed_offboard_entered_by_the_bridge_keeps_its_stream():
    """PX4: the bridge primed and entered OFFBOARD itself: dropping the stream then would make
    PX4 fall back to RTL one second later, so the primed hold goes on as the engaged stream."""
    fs = flying(Failsafe(), mode="AUTO.LOITER")
    fs.start_priming(0.0, 3.2)
    fs.on_vehicle(mode="OFFBOARD", armed=True, airborne=True, now=1.3)
    fs.end_priming(1.3, engage=True)
    assert fs.engaged
    tick = fs.tick(1.4, POSE)
    assert tick.send.type_mask == MASK_POSITION and tick.send.position.z == 5.0
    assert fs.tick(6.4, POSE).request == "land"  # 5 s without a commander after OFFBOARD


def test_no_ground_hold_in_arducopter_guided_until_airborne():
    """A commander's velocity expires on the ground in GUIDED: no hold at the ground pose (it
    would override a take-off); once airborne the contract's hold applies."""
    fs = Failsafe()
    fs.on_vehicle(mode="GUIDED", armed=True, airborne=False, now=0.0)
    fs.on_setpoint(velocity(), Kind.VELOCITY, 0.0)
    assert fs.engaged and fs.tick(0.1, POSE).send is not None  # the fresh command itself
    for t in (0.6, 1.5, 2.5):
        tick = fs.tick(t, POSE)
        assert tick.send is None and fs.state == "" and tick.request is None
    fs.on_vehicle(mode="GUIDED", armed=True, airborne=True, now=2.8)  # it lifted off
    tick = fs.tick(2.9, POSE)
    assert tick.send.type_mask == MASK_POSITION and fs.state == "hold"
    assert fs.tick(5.1, POSE).request == "land"


def test_offboard_holds_on_the_ground():
    """PX4: OFFBOARD on the ground needs the stream (to stay in the mode and to arm)."""
    fs = Failsafe()
    fs.on_vehicle(mode="OFFBOARD", armed=False, airborne=False, now=0.0)
    fs.on_setpoint(velocity(), Kind.VELOCITY, 0.0)
    assert fs.tick(0.6, POSE).send.type_mask == MASK_POSITION
