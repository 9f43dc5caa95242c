"""Quadrotor dynamics and the PX4-style position controller: gravity, ground, limits, response
times, determinism. Pure functions, simulated time only."""

from __future__ import annotations

import math

import pytest

from dronewrapper_sim.dynamics import (
    GRAVITY,
    ControlInput,
    QuadParams,
    QuadState,
    WindModel,
    step,
)
from dronewrapper_sim.px4.flight_control import NAN, PositionController, Target

DT = 1.0 / 250.0
P = QuadParams()


def run(state: QuadState, control: ControlInput, seconds: float, wind=(0.0, 0.0, 0.0)):
    for _ in range(round(seconds / DT)):
        state = step(state, control, P, DT, wind)
    return state


def fly(target: Target, seconds: float, state: QuadState | None = None, wind=None):
    """Closed loop: controller + dynamics; returns the final state."""
    ctrl = PositionController()
    state = state or QuadState(z=10.0, on_ground=False, thrust=GRAVITY)
    wind_model = wind or WindModel()
    for _ in range(round(seconds / DT)):
        state = step(state, ctrl.update(target, state, DT), P, DT, wind_model.step(DT))
    return state


def test_free_fall_follows_gravity_then_stops_on_the_ground():
    start = QuadState(z=20.0, on_ground=False)
    after = run(start, ControlInput(thrust=0.0), 1.0)
    # 1 s of fall: 0.5 g t^2 = 4.9 m, a little less with air drag
    assert 4.3 < 20.0 - after.z < 4.95
    assert -9.81 < after.vz < -8.0
    landed = run(after, ControlInput(thrust=0.0), 5.0)
    assert landed.z == 0.0
    assert landed.vz == 0.0
    assert landed.on_ground


def test_resting_on_the_ground_it_neither_sinks_nor_slides():
    state = QuadState()
    after = run(state, ControlInput(roll=0.4, pitch=0.4, thrust=0.5 * GRAVITY), 2.0)
    assert (after.x, after.y, after.z) == (0.0, 0.0, 0.0)
    assert after.on_ground
    assert (after.roll, after.pitch) == (0.0, 0.0)


def test_enough_thrust_lifts_off():
    after = run(QuadState(), ControlInput(thrust=1.5 * GRAVITY), 1.0)
    assert not after.on_ground
    assert after.z > 1.0


def test_hover_thrust_holds_altitude():
    state = QuadState(z=5.0, on_ground=False, thrust=GRAVITY)
    after = run(state, ControlInput(thrust=GRAVITY), 3.0)
    assert after.z == pytest.approx(5.0, abs=1e-6)


def test_airframe_tilt_and_thrust_limits():
    state = QuadState(z=50.0, on_ground=False, thrust=GRAVITY)
    after = run(state, ControlInput(roll=3.0, pitch=-3.0, thrust=100.0), 0.5)
    assert abs(after.roll) <= P.max_tilt_rad + 1e-9
    assert abs(after.pitch) <= P.max_tilt_rad + 1e-9
    assert after.thrust <= P.max_thrust_accel


def test_forward_pitch_accelerates_forward_along_heading():
    yaw = math.radians(90.0)  # facing north
    state = QuadState(z=50.0, on_ground=False, thrust=GRAVITY, yaw=yaw)
    after = run(state, ControlInput(pitch=0.2, thrust=GRAVITY / math.cos(0.2), yaw_rate=0), 1.0)
    assert after.vy > 1.0  # north
    assert abs(after.vx) < 0.05


def test_velocity_command_settles_like_px4_sih():
    """PX4 SIH: a 2 m/s command gives ~1.7 m/s after 5 s and ~1.8 m/s after 10 s."""
    target = Target(velocity=(2.0, 0.0, 0.0), yaw=0.0)
    v5 = fly(target, 5.0)
    v10 = fly(target, 10.0)
    assert 1.6 < v5.vx < 1.85
    assert 1.75 < v10.vx < 1.95
    assert v5.vx < v10.vx < 2.0
    assert abs(v10.z - 10.0) < 0.2  # altitude held while flying level


def test_velocity_response_time():
    ctrl = PositionController()
    state = QuadState(z=10.0, on_ground=False, thrust=GRAVITY)
    target = Target(velocity=(0.0, 2.0, 0.0), yaw=0.0)
    t = 0.0
    while state.vy < 0.63 * 2.0 * 0.85:  # 63 % of the settled value
        state = step(state, ctrl.update(target, state, DT), P, DT)
        t += DT
        assert t < 3.0
    assert 0.3 < t < 2.0


def test_speed_limits():
    fast = fly(Target(velocity=(30.0, 0.0, 0.0), yaw=0.0, max_xy=12.0), 15.0)
    assert 11.0 < math.hypot(fast.vx, fast.vy) <= 12.0 + 0.05
    up = fly(Target(velocity=(0.0, 0.0, 10.0), max_up=3.0), 4.0)
    assert up.vz == pytest.approx(3.0, abs=0.1)
    down = fly(
        Target(velocity=(0.0, 0.0, -10.0), max_down=1.5),
        3.0,
        QuadState(z=30.0, on_ground=False, thrust=GRAVITY),
    )
    assert down.vz == pytest.approx(-1.5, abs=0.1)


def test_tilt_limited_to_mpc_tiltmax_air():
    ctrl = PositionController()
    state = QuadState(z=10.0, on_ground=False, thrust=GRAVITY)
    worst = 0.0
    for _ in range(500):
        control = ctrl.update(Target(velocity=(12.0, 12.0, 0.0), max_xy=20.0), state, DT)
        tilt = math.acos(math.cos(control.roll) * math.cos(control.pitch))
        worst = max(worst, tilt)
        state = step(state, control, P, DT)
    assert math.radians(40.0) < worst <= ctrl.gains.max_tilt_rad + 1e-6


def test_position_target_is_reached_and_held():
    final = fly(Target(position=(5.0, -3.0, 12.0), yaw=1.0, max_xy=5.0), 12.0)
    assert final.x == pytest.approx(5.0, abs=0.1)
    assert final.y == pytest.approx(-3.0, abs=0.1)
    assert final.z == pytest.approx(12.0, abs=0.1)
    assert final.yaw == pytest.approx(1.0, abs=0.02)


def test_yaw_rate_command_turns_counter_clockwise():
    final = fly(Target(velocity=(0.0, 0.0, 0.0), yaw_rate=0.5), 2.0)
    lag = QuadParams().yaw_rate_tau_s
    assert final.yaw == pytest.approx(0.5 * (2.0 - lag), abs=0.05)  # minus the response lag


def test_nan_target_holds_instead_of_diverging():
    target = Target(velocity=(NAN, NAN, NAN))
    assert not target.is_valid()
    final = fly(target, 3.0, QuadState(z=10.0, vx=3.0, on_ground=False, thrust=GRAVITY))
    assert abs(final.vx) < 0.3
    assert all(math.isfinite(v) for v in (final.x, final.y, final.z))


def test_wind_pushes_the_vehicle_and_the_controller_holds_position():
    wind = WindModel(east_m_s=5.0)
    drift = run(
        QuadState(z=10.0, on_ground=False, thrust=GRAVITY),
        ControlInput(thrust=GRAVITY),
        3.0,
        (5.0, 0.0, 0.0),
    )
    assert drift.x > 1.0
    held = fly(Target(position=(0.0, 0.0, 10.0), yaw=0.0), 20.0, wind=wind)
    assert math.hypot(held.x, held.y) < 0.2


def test_same_seed_same_flight_different_seed_different_gusts():
    def flight(seed: int) -> QuadState:
        wind = WindModel(east_m_s=1.0, gust_m_s=2.0, seed=seed)
        return fly(Target(velocity=(1.0, 0.0, 0.0), yaw=0.0), 5.0, wind=wind)

    assert flight(7) == flight(7)
    assert flight(7) != flight(8)


def test_step_rejects_a_non_positive_dt():
    with pytest.raises(ValueError):
        step(QuadState(), ControlInput(), P, 0.0)
