"""A breach overrides its commander, and the commander is told: bridge_mavlink's pure core over
real MAVLink bytes, and bridge_tello's over its text protocol, publish a ``breach`` refusal
naming the limit crossed and the action taken to whoever sent the setpoints flown (the lease
holder first); a setpoint outside the envelope is told to its sender."""

from __future__ import annotations

from bridge_core_rig import OFFBOARD, CoreRig, velocity
from tello_core_rig import TelloRig

from dronewrapper.envelope import Envelope
from dronewrapper.msgs import registry
from dronewrapper.msgs.geometry import Point
from dronewrapper.msgs.mavros import FRAME_LOCAL_NED, MASK_POSITION, CommandTOL, PositionTarget
from dronewrapper_bridge_tello import operations as tello_ops


def refusals(rig: CoreRig) -> list:
    return rig.published(registry.REFUSAL)


def test_a_breach_is_told_to_the_commander_of_the_setpoints_flown():
    rig = CoreRig(upload_fence=False, envelope=Envelope(max_altitude=10, margin=1.0))
    rig.connect(mode=OFFBOARD, armed=True, flying=True)
    rig.run(0.2)
    rig.setpoint(velocity(0.5), commander="ada")
    assert refusals(rig) == []
    rig.pose(down=-12.0)  # blown above the ceiling
    rig.run(0.1)
    (told,) = refusals(rig)
    assert (told.commander, told.kind, told.what) == ("ada", "breach", "command")
    assert (told.limit, told.action) == ("max_altitude", "return")
    assert "altitude 12 m above the envelope's 10 m" in told.message
    assert told.text().startswith("command overridden (breach, max_altitude)")


def test_a_setpoint_outside_the_envelope_is_told_to_its_sender_with_the_limit():
    rig = CoreRig(upload_fence=False).connect(mode=OFFBOARD, armed=True, flying=True)
    rig.run(0.2)
    high = PositionTarget(
        coordinate_frame=FRAME_LOCAL_NED, type_mask=MASK_POSITION, position=Point(z=500.0)
    )
    rig.setpoint(high, commander="bob")
    (told,) = refusals(rig)
    assert (told.commander, told.kind, told.limit, told.count) == (
        "bob",
        "envelope",
        "max_altitude",
        1,
    )
    assert told.message == "altitude 500 m above the envelope's 120 m"
    assert told.header.stamp == rig.stamp


def test_a_tello_breach_is_told_to_the_lease_holder_with_the_landing():
    rig = TelloRig(envelope=Envelope(max_altitude=3.0, margin=0.5), command_lease=True)
    rig.connect()
    assert rig.call(tello_ops.takeoff, CommandTOL.takeoff(), commander="ada").success
    rig.run(0.5)
    rig.height_cm = 400  # blown up to 4 m
    rig.run(1.0)
    (told,) = rig.published(registry.REFUSAL)
    assert (told.commander, told.kind, told.limit) == ("ada", "breach", "max_altitude")
    assert told.action == "land"  # a Tello's return is a landing where it is
