"""Take-off and landing as non-blocking sequences, per autopilot, on the fake bus."""

from __future__ import annotations

import logging

import pytest
from bus_autopilot import BusAutopilot, drive

from dronewrapper.msgs.mavros import MASK_POSITION
from dronewrapper.runtime.commander import Commander
from dronewrapper.runtime.fake import FakeBus, FakeNode
from dronewrapper.runtime.flight import (
    FlightError,
    FlightSequence,
    Landing,
    NoReply,
    StepRefused,
    Takeoff,
    TooLate,
)

T0 = 1_700_000_000.0
PERIOD = 0.02  # s between the loop's wakes


class Loop:
    """A service loop running one sequence: steps it and streams the commander's setpoints."""

    def __init__(self, commander: Commander, sequence: FlightSequence) -> None:
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


def rig(**autopilot) -> tuple[FakeBus, BusAutopilot, Commander]:
    bus = FakeBus(start=T0)
    pilot = BusAutopilot(bus, **{"flying": False, **autopilot})
    pilot.tick(T0)
    node = FakeNode("svc", bus)
    commander = Commander(node, name="svc", inline_calls=True)
    pilot.tick(T0)
    return bus, pilot, commander


def fly(bus: FakeBus, pilot: BusAutopilot, loop: Loop, seconds: float) -> None:
    drive(bus, bus.clock() + seconds, pilot, loop, stop=lambda: loop.sequence.done)


def test_px4_holds_enters_offboard_arms_and_climbs_streaming_the_target():
    bus, pilot, c = rig()
    loop = Loop(c, Takeoff(c, 2.0, 10.0, T0))
    fly(bus, pilot, loop, 10.0)
    assert loop.sequence.done and loop.error is None
    assert [name for _, name in pilot.calls] == ["set_mode", "arming"]
    assert pilot.mode == "OFFBOARD" and pilot.z >= 1.9
    positions = [sp.position.z for _, sp in pilot.setpoints() if sp.type_mask == MASK_POSITION]
    assert positions[0] == 0.0 and positions[-1] == 2.0  # hold first, then the target
    assert c.target is not None and c.target.position.z == 2.0  # still streamed after
    assert bus.clock() - T0 == pytest.approx(2.0, abs=0.2)  # at 1 m/s


@pytest.mark.parametrize(
    ("autopilot", "calls"),
    [("ardupilotmega", ["set_mode", "arming", "takeoff"]), ("tello", ["takeoff"])],
)
def test_ardupilot_and_tello_take_off_by_command(autopilot, calls):
    bus, pilot, c = rig(autopilot=autopilot)
    loop = Loop(c, Takeoff(c, 1.5, 10.0, T0))
    fly(bus, pilot, loop, 10.0)
    assert loop.sequence.done and loop.error is None
    assert [name for _, name in pilot.calls] == calls and pilot.z >= 1.4
    assert pilot.setpoints() == []  # no setpoint stream needed


def test_already_flying_does_nothing_and_says_so(caplog):
    _, pilot, c = rig(flying=True)
    seq = Takeoff(c, 3.0, 10.0, T0)
    with caplog.at_level(logging.WARNING, logger="dronewrapper.flight"):
        assert seq.step(T0) and pilot.calls == [] and c.target is None
    (warning,) = caplog.records
    assert "already flying (z=2.00 m), so this does nothing" in warning.message


def test_a_refused_arming_names_the_reason_and_stops_the_hold_stream():
    _, _, c = rig(refuse={"arming": "Arming denied: no GPS"})
    seq = Takeoff(c, 2.0, 10.0, T0)
    with pytest.raises(FlightError, match=r"arming refused \(result 4\): Arming denied: no GPS"):
        seq.step(T0)
    assert seq.done and c.target is None and seq.step(T0 + 1)


def test_a_missing_server_fails_the_step_naming_it():
    _, _, c = rig(absent=["set_mode"])
    with pytest.raises(
        NoReply, match="set_mode OFFBOARD: no reply from drone/mavros/set_mode"
    ) as e:
        Takeoff(c, 2.0, 10.0, T0).step(T0)
    assert e.value.key == "drone/mavros/set_mode" and e.value.timeout == 10.0


def test_disarming_or_leaving_offboard_during_the_climb_fails():
    bus, pilot, c = rig()
    loop = Loop(c, Takeoff(c, 5.0, 20.0, T0))
    fly(bus, pilot, loop, 1.0)
    pilot.say("Failsafe: battery critical")
    pilot.armed = False  # e.g. a failsafe on the autopilot
    fly(bus, pilot, loop, 1.0)
    assert isinstance(loop.error, StepRefused) and loop.error.command == "takeoff"
    assert "the autopilot disarmed (Failsafe: battery critical)" in str(loop.error)

    bus, pilot, c = rig()
    loop = Loop(c, Takeoff(c, 5.0, 20.0, T0))
    fly(bus, pilot, loop, 1.0)
    pilot.mode = "AUTO.LOITER"  # the pilot took over
    fly(bus, pilot, loop, 1.0)
    assert loop.error is not None and "left OFFBOARD for AUTO.LOITER" in str(loop.error)


def test_the_climb_times_out_on_the_loop_clock():
    bus, pilot, c = rig()
    loop = Loop(c, Takeoff(c, 10.0, 3.0, T0))  # 10 m at 1 m/s cannot take 3 s
    fly(bus, pilot, loop, 10.0)
    assert isinstance(loop.error, TooLate) and "not reached within 3 s" in str(loop.error)
    assert bus.clock() - T0 == pytest.approx(3.0, abs=PERIOD + 1e-6)


def test_landing_stops_the_stream_calls_land_and_waits_for_the_ground():
    bus, pilot, c = rig(flying=True)
    c.set_velocity(0, 0, 0, 0, T0)
    loop = Loop(c, Landing(c, 10.0, T0))
    fly(bus, pilot, loop, 10.0)
    assert loop.sequence.done and loop.error is None
    assert pilot.called("land") == 1 and not pilot.armed and c.target is None


def test_landing_on_the_ground_disarmed_calls_nothing_and_a_refusal_is_named():
    _, pilot, c = rig()
    assert Landing(c, 10.0, T0).step(T0) and pilot.calls == []
    _, _, c = rig(flying=True, refuse={"land": "not now"})
    with pytest.raises(FlightError, match=r"land refused \(result 4\): not now"):
        Landing(c, 10.0, T0).step(T0)


def test_bad_arguments_are_refused():
    _, _, c = rig()
    with pytest.raises(ValueError, match="height"):
        Takeoff(c, 0.0, 10.0, T0)
    with pytest.raises(ValueError, match="timeout"):
        Landing(c, float("inf"), T0)
