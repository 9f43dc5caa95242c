"""The Tello failsafe contract with injected time: expiry -> rc 0 0 0 0, lost -> land."""

from __future__ import annotations

import pytest
from targets import velocity

from dronewrapper_bridge_tello.failsafe import Failsafe, FailsafeConfig
from dronewrapper_bridge_tello.sticks import Kind


def flying() -> Failsafe:
    fs = Failsafe()
    fs.on_flying(True)
    return fs


def test_fresh_setpoint_is_flown_then_a_real_stop_and_hover_on_expiry():
    fs = flying()
    fs.on_setpoint(velocity(), Kind.VELOCITY, 1.0)
    tick = fs.tick(1.4)
    assert tick.fly is not None and not tick.stop and fs.state == ""
    tick = fs.tick(1.55)
    assert tick.fly is None and tick.stop and fs.state == "hold"
    assert [(t.old, t.new) for t in tick.transitions] == [("", "hold")]
    assert fs.tick(1.9).stop  # repeated for stop_repeat_s (UDP may lose one)
    fs.on_sent(1.9)
    assert not fs.tick(2.2).stop  # then quiet ...
    assert fs.tick(1.9 + 3.0).stop  # ... until the keep-alive


def test_fresh_setpoint_leaves_hold():
    fs = flying()
    fs.on_setpoint(velocity(), Kind.VELOCITY, 0.0)
    fs.tick(1.0)
    fs.on_setpoint(velocity(0.2), Kind.VELOCITY, 1.2)
    tick = fs.tick(1.25)
    assert fs.state == "" and tick.fly[0].velocity.x == 0.2


def test_commander_lost_lands_once():
    fs = flying()
    fs.on_setpoint(velocity(), Kind.VELOCITY, 0.0)
    for t in (1.0, 3.0, 4.9):
        assert fs.tick(t).request is None
    tick = fs.tick(5.05)
    assert tick.request == "land" and fs.state == "land"
    assert fs.tick(5.2).request is None
    fs.on_flying(False)
    assert fs.state == ""


def test_hold_action_keeps_hovering_with_keepalive():
    fs = Failsafe(FailsafeConfig(commander_lost_action="hold"))
    fs.on_flying(True)
    fs.on_setpoint(velocity(), Kind.VELOCITY, 0.0)
    fs.on_sent(0.5)
    requests = [fs.tick(t / 10).request for t in range(5, 300)]
    assert set(requests) == {None} and fs.state == "hold"


def test_no_commander_no_landing_and_keepalive_after_takeoff():
    fs = flying()  # took off, nobody steers: the bridge keeps the Tello alive, never lands
    fs.on_sent(0.0)
    assert not fs.tick(2.0).stop
    tick = fs.tick(3.0)
    assert tick.stop and tick.request is None
    fs.on_sent(3.0)
    assert fs.tick(20.0).request is None and fs.state == ""


def test_nothing_is_sent_on_the_ground():
    fs = Failsafe()
    fs.on_setpoint(velocity(), Kind.VELOCITY, 0.0)
    assert not fs.engaged
    assert fs.tick(10.0).request is None and fs.state == ""


def test_config_is_checked():
    with pytest.raises(ValueError):
        FailsafeConfig(commander_lost_action="return")
    with pytest.raises(ValueError):
        FailsafeConfig(keepalive_s=20.0)
    with pytest.raises(ValueError):
        FailsafeConfig(setpoint_timeout=6.0)
