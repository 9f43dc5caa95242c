"""Take-off and landing through DroneWrapper on the fake bus, in bus time (SdkRig).

One request each, flown by the bridge (a BusAutopilot here): its answer at altitude, its
refusals, timeouts and cancellation as the app sees them. The rest of the wrapper's logic on
the fake bus: test_sdk_drone.py.
"""

from __future__ import annotations

import threading
from collections.abc import Iterator

import pytest
from bus_autopilot import REFUSED, SdkRig

from dronewrapper import Cancelled, CommandRefused, Timeout
from dronewrapper.msgs.mavros import LANDED_STATE_ON_GROUND


@pytest.fixture
def rig() -> Iterator[SdkRig]:
    rig = SdkRig({"x": 1.0})
    yield rig
    rig.close()


def names(rig: SdkRig) -> list[str]:
    return [name for _, name in rig.pilot.calls]


def test_takeoff_is_one_request_answered_at_altitude(rig):
    drone, pilot = rig.drone, rig.pilot
    start = rig.bus.clock()
    drone.takeoff(h=1.0, timeout=20)
    assert drone.get_position()[2] >= 0.9
    assert rig.bus.clock() - start == pytest.approx(0.9, abs=0.1)  # 1 m/s, back on arrival
    assert names(rig) == ["flight_takeoff"]
    assert (pilot.requests[0].height, pilot.requests[0].timeout) == (1.0, 20.0)
    assert drone.commanding is None and rig.pilot.setpoints() == []  # the bridge holds it
    assert drone.is_flying()
    drone.takeoff(h=3.0)  # idempotent: the bridge does nothing while flying
    assert pilot.goal == pytest.approx(1.0)
    drone.land(timeout=20)
    assert names(rig)[-1] == "flight_land" and pilot.requests[-1].timeout == 20.0
    assert drone.get_landed_state() == LANDED_STATE_ON_GROUND and not drone.get_state().armed


@pytest.mark.parametrize("autopilot", ["px4", "ardupilotmega", "tello"])
def test_takeoff_is_the_same_request_for_every_aircraft(autopilot):
    rig = SdkRig({"autopilot": autopilot})
    rig.drone.takeoff(h=1.0, timeout=20)
    assert names(rig) == ["flight_takeoff"] and rig.pilot.requests[-1].height == 1.0
    assert rig.drone.get_position()[2] >= 0.9
    rig.close()


def test_land_stops_the_stream_first(rig):
    rig.pilot.armed, rig.pilot.z = True, 2.0
    rig.drone.set_cmd_vel(vx=0.5)
    rig.drone.land(timeout=20)
    assert rig.drone.commanding is None
    last_setpoint = rig.pilot.setpoints()[-1][0]
    assert last_setpoint <= rig.pilot.calls[-1][0]  # nothing streamed after the request


def test_takeoff_refusal_carries_the_bridges_step_reason_and_result(rig):
    rig.pilot.refuse["flight_takeoff"] = "Arming denied: preflight checks failed"
    with pytest.raises(CommandRefused) as info:
        rig.drone.takeoff(h=1.0, timeout=10)
    reason = rig.pilot.refuse["flight_takeoff"]
    assert str(info.value) == f"takeoff refused (result {REFUSED}): {reason}"
    assert info.value.command == "takeoff" and info.value.result == REFUSED
    assert rig.drone.status_texts[-1].text == reason


def test_takeoff_timeout_names_the_altitude_mode_and_arming(rig):
    start = rig.bus.clock()
    with pytest.raises(
        Timeout,
        match=r"altitude 5\.00 m not reached within 0\.5 s \(now z=0\.\d\d m, mode OFFBOARD, "
        r"armed True\)",
    ):
        rig.drone.takeoff(h=5.0, timeout=0.5)
    assert rig.bus.clock() - start == pytest.approx(0.5, abs=0.021)


def test_the_autopilot_giving_up_the_climb_is_a_refusal_with_its_text(rig):
    def failsafe() -> None:
        rig.pilot.say("Failsafe: battery critical")
        rig.pilot.armed = False

    rig.at(0.3, failsafe)
    with pytest.raises(CommandRefused, match=r"takeoff refused: the autopilot disarmed \(Fail"):
        rig.drone.takeoff(h=2.0, timeout=10)


def test_the_pilot_taking_over_during_the_climb_is_a_refusal(rig):
    rig.at(0.3, lambda: setattr(rig.pilot, "mode", "POSCTL"))
    with pytest.raises(CommandRefused, match="the autopilot left OFFBOARD for POSCTL"):
        rig.drone.takeoff(h=2.0, timeout=10)


def test_a_cancelled_takeoff_stops_the_climb_at_once_and_stops_commanding(rig):
    drone = rig.drone
    cancel = threading.Event()
    heights: list[float] = []

    def cancel_mid_climb() -> None:  # another thread's cancel; bus time stands still until
        heights.append(rig.pilot.z)  # the SDK's cancel has reached the bridge
        cancel.set()
        assert rig.pilot.cancel_heard.wait(10), "the SDK sent no cancel"

    rig.at(0.4, cancel_mid_climb)
    start = rig.bus.clock()
    with pytest.raises(Cancelled, match="takeoff cancelled"):
        drone.takeoff(h=2.0, timeout=20, cancel=cancel)
    # the bridge's take-off ended on the cancel, mid-climb, not at its height
    assert rig.bus.clock() - start == pytest.approx(0.4, abs=0.1)
    assert drone.commanding is None and names(rig) == ["flight_takeoff", "flight_cancel"]
    stopped, z = rig.bus.clock(), rig.pilot.z
    assert z == pytest.approx(heights[0], abs=0.06) and z < 0.6
    rig.run(1.0)
    assert rig.pilot.z == pytest.approx(z)  # the climb stopped: it holds there
    assert rig.pilot.setpoints(since=stopped + 1e-9) == []
