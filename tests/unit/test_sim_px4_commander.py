"""The simulated PX4 commander as a pure state machine, time injected: arming rules,
auto-disarm, the offboard-loss failsafe and its actions, RTL and landing detection."""

from __future__ import annotations

import pytest
from pymavlink.dialects.v20 import common as mavlink

from dronewrapper_sim.dynamics import QuadState
from dronewrapper_sim.px4 import offboard, params
from dronewrapper_sim.px4.commander import ARM_DENIED, Commander, LandedState
from dronewrapper_sim.px4.modes import Mode

DT = 1.0 / 250.0
ZERO3 = (0.0, 0.0, 0.0)


# ---- commander (time injected) ----


def ground() -> QuadState:
    return QuadState()


def flying(z: float = 5.0, x: float = 0.0) -> QuadState:
    return QuadState(x=x, z=z, on_ground=False)


def velocity_sp(vz_up: float = 0.0) -> offboard.OffboardSetpoint:
    sp = offboard.parse(1, 1991, ZERO3, (0.0, 0.0, -vz_up), ZERO3, 0.0, 0.0, 0.0)
    assert isinstance(sp, offboard.OffboardSetpoint)
    return sp


def test_offboard_mode_accepted_disarmed_but_arming_refused_without_stream():
    cmd = Commander(params.ParamStore(), ground())
    assert cmd.set_mode(Mode.OFFBOARD, 0.0, ground()) == mavlink.MAV_RESULT_ACCEPTED
    assert cmd.nav_mode is Mode.OFFBOARD
    assert cmd.arm(0.1, ground()) == mavlink.MAV_RESULT_TEMPORARILY_REJECTED
    assert [t.text for t in cmd.drain_texts()] == [ARM_DENIED]
    assert not cmd.armed
    for i in range(5):
        cmd.on_setpoint(velocity_sp(), 0.2 + 0.05 * i)
    assert cmd.arm(0.5, ground()) == mavlink.MAV_RESULT_ACCEPTED
    assert cmd.armed


def test_arming_rules_for_other_modes():
    cmd = Commander(params.ParamStore(), ground())
    assert (
        cmd.set_mode(Mode.POSCTL, 0.0, ground()) == mavlink.MAV_RESULT_ACCEPTED
    )  # disarmed: always accepted
    assert cmd.arm(0.0, ground()) == mavlink.MAV_RESULT_TEMPORARILY_REJECTED  # needs RC
    assert cmd.arm(0.0, ground(), force=True) == mavlink.MAV_RESULT_ACCEPTED
    cmd2 = Commander(params.ParamStore(), ground())
    assert cmd2.nav_mode is Mode.LOITER  # boots in Hold
    assert cmd2.arm(0.0, ground()) == mavlink.MAV_RESULT_ACCEPTED
    # armed: switching to a mode that cannot run is refused
    assert cmd2.set_mode(Mode.OFFBOARD, 0.5, ground()) == mavlink.MAV_RESULT_TEMPORARILY_REJECTED
    assert cmd2.set_mode(Mode.POSCTL, 0.5, ground()) == mavlink.MAV_RESULT_TEMPORARILY_REJECTED
    texts = [t.text for t in cmd2.drain_texts()]
    assert "Switching to Offboard is currently not available" in texts


def test_preflight_auto_disarm_after_com_disarm_prflt():
    cmd = Commander(params.ParamStore(), ground())
    assert cmd.arm(0.0, ground()) == mavlink.MAV_RESULT_ACCEPTED
    t = 0.0
    while cmd.armed and t < 20.0:
        t += 0.01
        cmd.update(t, ground())
    assert t == pytest.approx(10.0, abs=0.02)
    assert "Disarmed by auto preflight disarming" in [x.text for x in cmd.drain_texts()]


def test_disarm_refused_in_the_air_unless_forced():
    cmd = Commander(params.ParamStore(), ground())
    cmd.arm(0.0, ground())
    cmd.update(1.0, flying())  # take-off detected
    assert not cmd.landed
    assert cmd.disarm(1.1, flying()) == mavlink.MAV_RESULT_TEMPORARILY_REJECTED
    assert cmd.armed
    assert cmd.disarm(1.2, flying(), force=True) == mavlink.MAV_RESULT_ACCEPTED


def streaming_flight(cmd: Commander, until: float, t: float = 0.0, period: float = 0.05):
    """Stream setpoints every ``period`` s until ``until``, vehicle flying at 5 m."""
    while t < until:
        t = round(t + DT, 6)
        if round(t / period, 6).is_integer():
            cmd.on_setpoint(velocity_sp(), t)
        cmd.update(t, flying())
    return t


def test_offboard_loss_failsafe_after_com_of_loss_t_and_unlatched_return():
    cmd = Commander(params.ParamStore(), ground())
    cmd.on_setpoint(velocity_sp(), 0.0)
    cmd.set_mode(Mode.OFFBOARD, 0.0, ground())
    cmd.arm(0.0, ground())
    t = streaming_flight(cmd, 3.0)
    assert cmd.nav_mode is Mode.OFFBOARD and not cmd.landed
    last = cmd.setpoint_at
    cmd.drain_texts()
    while cmd.nav_mode is Mode.OFFBOARD and t < last + 3.0:  # stream stopped
        t += DT
        cmd.update(t, flying())
    assert t - last == pytest.approx(1.0, abs=2 * DT)  # COM_OF_LOSS_T
    assert cmd.nav_mode is Mode.RTL  # COM_OBL_RC_ACT 0 needs RC -> NAV_RCL_ACT 2 = Return
    assert cmd.user_mode is Mode.OFFBOARD  # still what the user wants
    assert cmd.failsafe
    assert "Failsafe activated" in [x.text for x in cmd.drain_texts()]
    cmd.update(t + 0.5, flying())
    resumed = t + 0.5
    cmd.on_setpoint(velocity_sp(), resumed)
    cmd.update(resumed + DT, flying())
    assert cmd.nav_mode is Mode.OFFBOARD  # back within one step, no mode command
    assert not cmd.failsafe


def test_gaps_shorter_than_com_of_loss_t_keep_offboard():
    cmd = Commander(params.ParamStore(), ground())
    cmd.on_setpoint(velocity_sp(), 0.0)
    cmd.set_mode(Mode.OFFBOARD, 0.0, ground())
    cmd.arm(0.0, ground())
    streaming_flight(cmd, 8.0, period=0.8)  # 1.25 Hz: PX4 keeps OFFBOARD
    assert cmd.nav_mode is Mode.OFFBOARD and not cmd.failsafe


@pytest.mark.parametrize(
    ("obl", "rcl", "expected"),
    [
        (0, 2, Mode.RTL),
        (0, 3, Mode.LAND),
        (0, 1, Mode.LOITER),
        (4, 2, Mode.LAND),
        (5, 2, Mode.LOITER),
    ],
)
def test_failsafe_action_follows_params(obl, rcl, expected):
    store = params.ParamStore({"COM_OBL_RC_ACT": obl, "NAV_RCL_ACT": rcl})
    cmd = Commander(store, ground())
    cmd.on_setpoint(velocity_sp(), 0.0)
    cmd.set_mode(Mode.OFFBOARD, 0.0, ground())
    cmd.arm(0.0, ground())
    t = streaming_flight(cmd, 2.0)
    cmd.update(t + 1.5, flying())
    assert cmd.nav_mode is expected


def test_rtl_far_from_home_climbs_first_close_to_home_lands():
    far = Commander(params.ParamStore(), ground())
    far.arm(0.0, ground())
    far.update(1.0, flying(z=5.0, x=12.0))
    far.set_mode(Mode.RTL, 1.0, flying(z=5.0, x=12.0))
    far.update(1.01, flying(z=5.0, x=12.0))
    assert far.target.position[2] == pytest.approx(30.0)  # RTL_RETURN_ALT
    assert far.landed_state is LandedState.IN_AIR
    near = Commander(params.ParamStore(), ground())
    near.arm(0.0, ground())
    near.update(1.0, flying(z=5.0, x=3.0))
    near.set_mode(Mode.RTL, 1.0, flying(z=5.0, x=3.0))
    near.update(1.01, flying(z=5.0, x=3.0))
    assert near.target.velocity[2] < 0  # descending straight away
    assert near.landed_state is LandedState.LANDING
    assert "RTL: land at destination" in [t.text for t in near.drain_texts()]


def test_landing_detection_and_disarm_then_user_mode_restored():
    cmd = Commander(params.ParamStore(), ground())
    cmd.on_setpoint(velocity_sp(), 0.0)
    cmd.set_mode(Mode.OFFBOARD, 0.0, ground())
    cmd.arm(0.0, ground())
    t = streaming_flight(cmd, 2.0)
    assert cmd.set_mode(Mode.LAND, t, flying()) == mavlink.MAV_RESULT_ACCEPTED
    cmd.update(t + 0.01, flying(z=2.0))
    assert cmd.landed_state is LandedState.LANDING
    touchdown = t + 1.0
    t = touchdown
    while cmd.armed and t < touchdown + 10:
        t += 0.01
        cmd.update(t, ground())
    texts = [x.text for x in cmd.drain_texts()]
    assert "Landing detected" in texts and "Disarmed by landing" in texts
    assert t - touchdown == pytest.approx(1.0 + 2.0, abs=0.03)  # LNDMC_TRIG_TIME + DISARM_LAND
    assert cmd.nav_mode is Mode.OFFBOARD  # the intended mode again, as PX4 reports it
