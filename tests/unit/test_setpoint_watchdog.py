"""The setpoint watchdog every bridge shares (dronewrapper_bridge_base.setpoint_watchdog), in given
time."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import ClassVar

import pytest
from targets import velocity

from dronewrapper_bridge_base.guided_failsafe import FailsafeConfig as MavlinkFailsafeConfig
from dronewrapper_bridge_base.setpoint_watchdog import (
    HOLD,
    LAND,
    NONE,
    RETURN,
    SetpointWatchdog,
    Transition,
    WatchdogConfig,
)
from dronewrapper_bridge_tello.failsafe import FailsafeConfig as TelloFailsafeConfig

TARGET = velocity(1.0)


def steered(config: WatchdogConfig | None = None, at: float = 10.0) -> SetpointWatchdog[str]:
    lease: SetpointWatchdog[str] = SetpointWatchdog(config or WatchdogConfig())
    lease.take_setpoint(TARGET, "velocity", at)
    lease.engaged = True
    return lease


def test_fresh_until_setpoint_timeout_then_stale():
    lease = steered()
    assert lease.is_fresh(10.5) and not lease.is_fresh(10.51)
    assert lease.target is TARGET and lease.kind == "velocity"
    assert lease.setpoint_age(11.0) == pytest.approx(1.0) and lease.stale_at() == 10.5


def test_no_setpoint_is_never_fresh():
    lease: SetpointWatchdog[str] = SetpointWatchdog(WatchdogConfig())
    assert not lease.is_fresh(0.0) and lease.setpoint_age(0.0) == math.inf
    assert lease.commander_lost(100.0, in_control=True) == LAND  # in control, nothing came
    lease = SetpointWatchdog(WatchdogConfig())
    assert lease.commander_lost(100.0, in_control=False) == ""


def test_hold_then_a_fresh_setpoint_ends_it():
    lease = steered()
    lease.hold(": hover")
    assert lease.state == HOLD
    lease.hold()  # once
    lease.take_setpoint(TARGET, "velocity", 11.0)
    assert lease.state == NONE
    assert lease.transitions() == [
        Transition(NONE, HOLD, "no setpoint for 0.5 s: hover"),
        Transition(HOLD, NONE, "fresh setpoint"),
    ]
    assert lease.transitions() == []


@pytest.mark.parametrize("action", [LAND, RETURN])
def test_commander_lost_after_its_timeout_once(action):
    lease = steered(WatchdogConfig(commander_lost_action=action))
    assert lease.commander_lost(15.0, in_control=True) == ""  # exactly 5 s: not yet
    assert lease.commander_lost(15.01, in_control=True) == action
    assert lease.state == action
    assert lease.commander_lost(16.0, in_control=True) == ""  # issued once
    (transition,) = lease.transitions()
    assert transition.new == action and "commander lost" in transition.reason


def test_commander_lost_counts_from_since_and_needs_control():
    lease = steered()
    assert lease.commander_lost(20.0, in_control=False) == ""
    assert lease.commander_lost(20.0, in_control=True, since=16.0) == ""  # 4 s since then
    assert lease.commander_lost(21.5, in_control=True, since=16.0) == LAND


def test_hold_action_never_acts():
    lease = steered(WatchdogConfig(commander_lost_action=HOLD))
    assert lease.commander_lost(1e6, in_control=True) == "" and lease.state == NONE


def test_forget_setpoint_drops_it_and_the_engagement():
    lease = steered()
    lease.forget_setpoint()
    assert lease.target is None and not lease.engaged and not lease.is_fresh(10.0)
    assert lease.last_setpoint == -math.inf


def test_config_is_checked_and_names_the_problem():
    with pytest.raises(ValueError, match="commander_lost_action"):
        WatchdogConfig(commander_lost_action="panic")
    with pytest.raises(ValueError, match="setpoint_timeout < commander_lost_timeout"):
        WatchdogConfig(setpoint_timeout=6.0)
    with pytest.raises(ValueError, match="setpoint_timeout"):
        WatchdogConfig(setpoint_timeout=math.nan)


def test_each_bridge_narrows_the_actions_it_can_fly():
    @dataclass(frozen=True)
    class NoReturn(WatchdogConfig):
        ACTIONS: ClassVar[tuple[str, ...]] = (HOLD, LAND)

    with pytest.raises(ValueError, match="one of hold, land"):
        NoReturn(commander_lost_action=RETURN)
    with pytest.raises(ValueError, match="one of hold, land,"):
        TelloFailsafeConfig(commander_lost_action=RETURN)  # a Tello has no return
    assert MavlinkFailsafeConfig(commander_lost_action=RETURN).commander_lost_action == RETURN
    assert isinstance(TelloFailsafeConfig(), WatchdogConfig)
    assert isinstance(MavlinkFailsafeConfig(), WatchdogConfig)
