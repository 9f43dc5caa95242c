"""bridge_tello's take-off and landing operations on the pure core, with real SDK strings."""

from __future__ import annotations

import pytest
from tello_core_rig import TelloRig

from dronewrapper.envelope import Envelope
from dronewrapper.msgs import flight
from dronewrapper.msgs.mavros import LANDED_STATE_ON_GROUND
from dronewrapper_bridge_base.core_driver import cancel_steps
from dronewrapper_bridge_tello.flight import land_here, takeoff_to


def connected(**config) -> TelloRig:
    rig = TelloRig(**config)
    rig.connect()
    return rig


def test_takeoff_then_up_to_the_height_and_the_message_says_so():
    rig = connected()
    reply = rig.call(takeoff_to, flight.TakeoffRequest(height=2.5))
    assert rig.commands()[-2:] == ["takeoff", "up 150"]
    assert reply.success and reply.height == pytest.approx(2.5)
    assert reply.message == (
        "took off: the Tello's take-off ended at 1.00 m, then up 150 to the 2.5 m asked"
    )


def test_a_height_near_the_tellos_own_take_off_needs_no_move():
    rig = connected()
    reply = rig.call(takeoff_to, flight.TakeoffRequest(height=1.05))
    assert reply.success and rig.commands()[-1] == "takeoff"
    assert reply.message == "took off: the Tello's take-off ended at 1.00 m, as asked"


def test_a_refused_take_off_or_move_is_named_with_the_tellos_text():
    rig = connected()
    rig.script["takeoff"] = "error Motor stop"
    reply = rig.call(takeoff_to, flight.TakeoffRequest(height=2.0))
    assert (reply.failure, reply.step) == (flight.REFUSED, "takeoff")
    assert "error Motor stop" in reply.message
    rig = connected()
    rig.script["up 100"] = "error Not joystick"
    reply = rig.call(takeoff_to, flight.TakeoffRequest(height=2.0))
    assert (reply.failure, reply.step) == (flight.REFUSED, "up 100")


def test_a_take_off_that_ends_after_its_timeout_is_too_late():
    rig = connected()
    rig.delays["takeoff"] = 3.0
    reply = rig.call(takeoff_to, flight.TakeoffRequest(height=2.0, timeout=2.0))
    assert reply.failure == flight.TOO_LATE


def test_already_flying_or_not_connected_sends_nothing():
    rig = connected()
    assert rig.call(takeoff_to, flight.TakeoffRequest(height=2.0)).success
    since = rig.now
    reply = rig.call(takeoff_to, flight.TakeoffRequest(height=3.0))
    assert reply.success and reply.message.startswith("already flying (z=2.00 m)")
    assert rig.commands(since) == []
    fresh = TelloRig()
    assert fresh.call(takeoff_to, flight.TakeoffRequest(height=2.0)).failure == flight.NOT_READY
    with pytest.raises(ValueError, match="height"):
        rig.call(takeoff_to, flight.TakeoffRequest(height=31.0))


def test_landing_is_done_on_the_tellos_ok():
    rig = connected()
    assert rig.call(takeoff_to, flight.TakeoffRequest(height=1.0)).success
    reply = rig.call(land_here, flight.LandRequest())
    assert reply.success and rig.commands()[-1] == "land"
    assert rig.core.telemetry.landed.state == LANDED_STATE_ON_GROUND
    again = rig.call(land_here, flight.LandRequest())
    assert again.success and again.message == "already on the ground"
    rig.script["land"] = "error"
    assert rig.call(takeoff_to, flight.TakeoffRequest(height=1.0)).success
    assert rig.call(land_here, flight.LandRequest()).failure == flight.REFUSED


def test_a_take_off_above_the_envelope_is_refused_before_anything_is_sent():
    rig = connected(envelope=Envelope(max_altitude=3.0))
    since = rig.now
    reply = rig.call(takeoff_to, flight.TakeoffRequest(height=4.0))
    assert (reply.success, reply.failure, reply.step) == (False, flight.REFUSED, "takeoff")
    assert "4 m above the envelope's 3 m" in reply.message and rig.commands(since) == []


def test_a_cancel_mid_climb_ends_the_take_off_and_sends_stop():
    rig = connected()
    rig.delays["up 200"] = 3.0  # the move to the height takes 3 s
    takeoff = rig.start(takeoff_to, flight.TakeoffRequest(height=3.0))
    rig.run(10.0, until=lambda: "up 200" in rig.commands())
    rig.run(1.0)
    cancelled_at = rig.now
    reply = rig.call(cancel_steps, flight.CancelRequest())
    assert reply.success and takeoff.done and takeoff.result().failure == flight.CANCELLED
    rig.run(1.0)
    assert rig.commands(since=cancelled_at) == ["stop"]
