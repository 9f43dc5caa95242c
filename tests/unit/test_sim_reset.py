"""Resetting a simulated vehicle: back at its start pose, on the ground, motors off."""

from __future__ import annotations

import math

from dronewrapper_sim.px4.autopilot import Autopilot, AutopilotConfig
from dronewrapper_sim.tello.flight import Phase, TelloFlight


def test_a_flying_tello_is_put_back_at_its_start_landed():
    flight = TelloFlight(start=(1.0, 2.0, 0.5), battery_percent=80.0)
    flight.takeoff()
    for _ in range(600):
        flight.step(0.01)
    flight.set_rc(0.0, 0.5, 0.0, 0.3)
    for _ in range(100):
        flight.step(0.01)
    assert flight.flying and flight.state.z > 0.5
    battery = flight.battery_percent
    flight.reset_to_start()
    s = flight.state
    assert (s.x, s.y, s.z, s.yaw) == (1.0, 2.0, 0.0, 0.5)
    assert (s.vx, s.vy, s.vz) == (0.0, 0.0, 0.0)
    assert flight.phase is Phase.LANDED and not flight.motors_on
    assert flight.battery_percent == battery  # a reset is not a new battery
    for _ in range(100):
        flight.step(0.01)  # it stays put: no stick or path left over
    assert math.hypot(flight.state.x - 1.0, flight.state.y - 2.0) < 1e-6
    flight.takeoff()  # and flies again
    for _ in range(600):
        flight.step(0.01)
    assert flight.flying


def test_an_armed_iris_in_flight_is_put_back_at_its_start_disarmed():
    autopilot = Autopilot(AutopilotConfig(start_x=3.0, start_y=-1.0, start_yaw=1.0), {})
    autopilot.commander.arm(0.0, autopilot.state, force=True)
    autopilot.state = autopilot.state.__class__(x=10.0, y=5.0, z=4.0, vx=2.0, yaw=0.2)
    assert autopilot.armed
    autopilot.reset_to_start()
    s = autopilot.state
    assert (s.x, s.y, s.z, s.vx, s.yaw) == (3.0, -1.0, 0.0, 0.0, 1.0)
    assert not autopilot.armed
    for _ in range(250):
        autopilot.step(0.004)
    assert abs(autopilot.state.z) < 1e-3 and not autopilot.armed
