"""Take-off and landing as non-blocking sequences on the fake bus: one request each, the
bridge's reply mapped to its error."""

from __future__ import annotations

import logging

import pytest
from bus_autopilot import BusAutopilot, drive

from dronewrapper.client import DroneClient, flight
from dronewrapper.client.flight import (
    FlightError,
    FlightSequence,
    Landing,
    NoPosition,
    NoReply,
    NotReady,
    StepRefused,
    Takeoff,
    TooLate,
)
from dronewrapper.msgs.flight import NO_POSITION, REFUSED, TOO_LATE, FlightResult, TakeoffRequest
from dronewrapper.runtime.fake import FakeBus, FakeNode

T0 = 1_700_000_000.0
PERIOD = 0.02  # s between the loop's wakes


class Loop:
    """A service loop running one sequence: steps it and streams the commander's setpoints."""

    def __init__(self, commander: DroneClient, sequence: FlightSequence) -> None:
        self.commander = commander
        self.sequence = sequence
        self.error: FlightError | None = None

    def step(self, now: float) -> None:
        try:
            self.sequence.step(now)
        except FlightError as exc:
            self.error = exc
        self.commander.poll(now)

    def next_wake(self, now: float) -> float:
        return min(now + PERIOD, self.commander.next_due())


class Stepper:
    """Runs ``action`` at every wake of the bus (as the aircraft moves)."""

    def __init__(self, action) -> None:
        self.action = action

    def step(self, now: float) -> None:
        self.action()

    def next_wake(self, now: float) -> float:
        return now + PERIOD


def rig(**autopilot) -> tuple[FakeBus, BusAutopilot, DroneClient]:
    bus = FakeBus(start=T0)
    pilot = BusAutopilot(bus, **{"flying": False, **autopilot})
    pilot.tick(T0)
    node = FakeNode("svc", bus)
    commander = DroneClient(node, name="svc", inline_calls=True)
    pilot.tick(T0)
    return bus, pilot, commander


def fly(bus: FakeBus, pilot: BusAutopilot, loop: Loop, seconds: float) -> None:
    drive(bus, bus.clock() + seconds, pilot, loop, stop=lambda: loop.sequence.done)


def test_takeoff_is_one_request_and_the_climb_is_the_bridges():
    bus, pilot, c = rig()
    loop = Loop(c, Takeoff(c, 2.0, 10.0, T0))
    fly(bus, pilot, loop, 10.0)
    assert loop.sequence.done and loop.error is None
    assert [name for _, name in pilot.calls] == ["flight_takeoff"]
    assert pilot.requests[0] == TakeoffRequest(height=2.0, timeout=10.0, tolerance=0.1)
    assert loop.sequence.result.success and pilot.z >= 1.9
    assert pilot.setpoints() == [] and c.target is None  # nothing streamed by the loop
    assert bus.clock() - T0 == pytest.approx(2.0, abs=0.2)  # at 1 m/s, in bus time


@pytest.mark.parametrize("autopilot", ["px4", "ardupilotmega", "tello"])
def test_every_aircraft_gets_the_same_request(autopilot):
    bus, pilot, c = rig(autopilot=autopilot)
    loop = Loop(c, Takeoff(c, 1.5, 10.0, T0))
    fly(bus, pilot, loop, 10.0)
    assert loop.error is None and [name for _, name in pilot.calls] == ["flight_takeoff"]


def test_already_flying_does_nothing_and_says_so(caplog):
    _, pilot, c = rig(flying=True)
    seq = Takeoff(c, 3.0, 10.0, T0)
    with caplog.at_level(logging.WARNING, logger="dronewrapper.flight"):
        assert seq.step(T0) and pilot.goal == 2.0
    (warning,) = caplog.records
    assert "already flying (z=2.00 m)" in warning.message


def test_a_refusal_names_the_step_the_reason_and_the_result():
    _, _, c = rig(refuse={"flight_takeoff": "Arming denied: no GPS"})
    seq = Takeoff(c, 2.0, 10.0, T0)
    with pytest.raises(StepRefused, match=r"takeoff refused \(result 4\): Arming denied: no GPS"):
        seq.step(T0)
    assert seq.done and seq.step(T0 + 1)


def test_a_missing_server_is_no_reply_naming_the_key_and_the_time_waited():
    """A query no server takes ends after the 2 s a call asks again, not the 20 s allowed."""
    _, _, c = rig(absent=["flight_takeoff"])
    with pytest.raises(NoReply, match="takeoff: no reply from drone/dronewrapper/takeoff") as e:
        Takeoff(c, 2.0, 10.0, T0).step(T0)
    assert e.value.key == "drone/dronewrapper/takeoff" and e.value.timeout == 2.0


def test_disarming_or_leaving_the_mode_during_the_climb_fails():
    bus, pilot, c = rig()

    def failsafe() -> None:
        if pilot.z > 1.0:
            pilot.say("Failsafe: battery critical")
            pilot.armed = False  # e.g. a failsafe on the autopilot

    pilot.steppers = (pilot, Stepper(failsafe))
    loop = Loop(c, Takeoff(c, 5.0, 20.0, T0))
    fly(bus, pilot, loop, 10.0)
    assert isinstance(loop.error, StepRefused) and loop.error.command == "takeoff"
    assert "the autopilot disarmed (Failsafe: battery critical)" in str(loop.error)


def test_the_climb_times_out_in_the_bridges_time():
    bus, pilot, c = rig()
    loop = Loop(c, Takeoff(c, 10.0, 3.0, T0))  # 10 m at 1 m/s cannot take 3 s
    fly(bus, pilot, loop, 10.0)
    assert isinstance(loop.error, TooLate) and "not reached within 3 s" in str(loop.error)
    assert bus.clock() - T0 == pytest.approx(3.0, abs=PERIOD + 1e-6)


@pytest.mark.parametrize(
    ("failure", "error"),
    [(REFUSED, StepRefused), (TOO_LATE, TooLate), (NO_POSITION, NoPosition), ("x", NotReady)],
)
def test_each_failure_the_bridge_reports_is_its_error(failure, error):
    reply = FlightResult(failure=failure, step="arming", result=1, message="why")
    assert isinstance(flight.failure("takeoff", reply), error)
    assert "why" in str(flight.failure("takeoff", reply))


def test_landing_stops_the_stream_then_asks_once_and_waits_for_the_ground():
    bus, pilot, c = rig(flying=True)
    c.set_velocity(0, 0, 0, 0, T0)
    loop = Loop(c, Landing(c, 10.0, T0))
    fly(bus, pilot, loop, 10.0)
    assert loop.sequence.done and loop.error is None
    assert pilot.called("flight_land") == 1 and not pilot.armed and c.target is None


def test_a_refused_landing_is_named():
    _, _, c = rig(flying=True, refuse={"flight_land": "not now"})
    with pytest.raises(FlightError, match=r"land refused \(result 4\): not now"):
        Landing(c, 10.0, T0).step(T0)


def test_bad_arguments_are_refused():
    _, _, c = rig()
    with pytest.raises(ValueError, match="height"):
        Takeoff(c, 0.0, 10.0, T0)
    with pytest.raises(ValueError, match="timeout"):
        Landing(c, float("inf"), T0)
