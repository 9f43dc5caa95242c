"""A script chooses the telemetry streams it receives (``DroneWrapper(streams=...)``): the
flight's three always, the others on their first read; a wrong name is refused before any
network. On the fake bus, in bus time (tests/bus_autopilot.py SdkRig)."""

from __future__ import annotations

import pytest
from bus_autopilot import TELEMETRY_PERIOD_S, SdkRig

from dronewrapper import DroneWrapper, InvalidArgument, NoData
from dronewrapper.client.inputs import FLIGHT_STREAMS, GETTER_STREAMS, STREAMS, chosen_streams
from dronewrapper.runtime.fake import FakeBus, FakeNode

pytestmark = pytest.mark.timeout(60)


def subscribed(drone: DroneWrapper) -> set[str]:
    """The named streams the drone's inputs hold (subscribed) now."""
    return {name for name in STREAMS if drone.client.inputs.subscribed(name)}


def test_by_default_every_getter_stream_is_received_from_the_start():
    rig = SdkRig()
    try:
        assert subscribed(rig.drone) == set(GETTER_STREAMS)
    finally:
        rig.close()


def test_a_script_receives_the_flight_streams_and_those_it_names_only():
    rig = SdkRig({"x": 1.0}, streams=["battery"])
    drone = rig.drone
    try:
        assert subscribed(drone) == {*FLIGHT_STREAMS, "battery"}
        assert drone.get_position().tolist() == [1.0, 0.0, 0.0]
        assert drone.get_battery() == pytest.approx(0.8)
        with pytest.raises(NoData):  # subscribed by this read: nothing received yet
            drone.get_velocity()
        assert "velocity_body" in subscribed(drone)
        rig.run(TELEMETRY_PERIOD_S)
        assert drone.get_velocity().tolist() == [0.0, 0.0, 0.0]
        drone.takeoff(h=0.6, timeout=20)  # the flight reads only its own streams
        assert drone.is_flying()
        drone.land(timeout=30)
        assert not rig.pilot.armed
    finally:
        rig.close()


def test_connecting_waits_for_the_chosen_streams_and_subscribes_no_other():
    rig = SdkRig({"x": 1.0}, streams=["battery"], wait=True, timeout=5.0)
    try:
        assert rig.drone.get_battery() == pytest.approx(0.8)  # waited for
        assert subscribed(rig.drone) == {*FLIGHT_STREAMS, "battery"}
    finally:
        rig.close()


@pytest.mark.parametrize(
    ("streams", "words"),
    [(["pose", "speed"], r"unknown streams \['speed'\]"), ("pose", "a list of names")],
)
def test_an_unknown_stream_is_refused_before_any_network(streams, words):
    bus = FakeBus()
    with pytest.raises(InvalidArgument, match=words):
        DroneWrapper("drone", node=FakeNode("app", bus), wait=False, streams=streams)
    assert not bus.matched("drone/**")  # nothing subscribed, nothing sent
    assert not bus.published


def test_chosen_streams_keep_the_flight_streams_first_and_once():
    assert chosen_streams(None) == GETTER_STREAMS
    assert chosen_streams(["pose", "link"]) == (*FLIGHT_STREAMS, "link")
    assert chosen_streams([]) == FLIGHT_STREAMS
