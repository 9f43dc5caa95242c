"""What a bridge refuses reaches the commander that sent it: both bridges' cores behind the
shared wiring on the fake bus, in bus time, a commander's 30 Hz stream refused for the lease,
for arriving late and for the envelope; each refusal reported within 0.1 s of the first
refused setpoint, and a refused stream reported about once a second, not 30 times."""

from __future__ import annotations

import pytest
from wired_bridge import Wired, wire

from dronewrapper.client import DroneClient
from dronewrapper.envelope import Envelope
from dronewrapper.msgs import refusal as refusals
from dronewrapper.msgs import registry
from dronewrapper.msgs.geometry import Point, Vector3
from dronewrapper.msgs.lease import LeaseRequest
from dronewrapper.msgs.mavros import (
    FRAME_BODY_NED,
    FRAME_LOCAL_NED,
    MASK_POSITION,
    MASK_VELOCITY,
    PositionTarget,
)
from dronewrapper.runtime.caller import commander_attachment
from dronewrapper.runtime.fake import FakeBus, FakeNode
from dronewrapper_bridge_mavlink import node as mavlink_node
from dronewrapper_bridge_mavlink.config import Config as MavlinkConfig
from dronewrapper_bridge_mavlink.core import BridgeCore
from dronewrapper_bridge_tello import node as tello_node
from dronewrapper_bridge_tello.config import Config as TelloConfig
from dronewrapper_bridge_tello.core import TelloCore

HOLD = PositionTarget(coordinate_frame=FRAME_BODY_NED, type_mask=MASK_VELOCITY)
EAST = PositionTarget(
    coordinate_frame=FRAME_BODY_NED, type_mask=MASK_VELOCITY, velocity=Vector3(x=1.0)
)
FAR = PositionTarget(
    coordinate_frame=FRAME_LOCAL_NED, type_mask=MASK_POSITION, position=Point(x=30.0, z=3.0)
)
PERIOD = 1 / 30
REPORTED_WITHIN_S = 0.1


def wired(kind: str, bus: FakeBus, *, lease: bool = False) -> Wired:
    fence = Envelope(fence=[(-10.0, -10.0), (10.0, -10.0), (10.0, 10.0), (-10.0, 10.0)])
    if kind == "mavlink":
        config = MavlinkConfig(command_lease=lease, envelope=fence)
        core, module = BridgeCore(config, bus.clock.monotonic()), mavlink_node
    else:
        config = TelloConfig(command_lease=lease, envelope=fence, video=False)
        core, module = TelloCore(config, bus.clock.monotonic()), tello_node
    return wire(core, module, bus)


def stream(bus: FakeBus, commander: DroneClient, target: PositionTarget, seconds: float) -> None:
    """The commander streams ``target`` at 30 Hz for ``seconds`` of bus time."""
    commander.set(target, bus.clock.monotonic())
    end = bus.clock.monotonic() + seconds
    while bus.clock.monotonic() < end - 1e-9:
        bus.clock.advance_to(bus.clock.monotonic() + PERIOD)
        commander.poll(bus.clock.monotonic())


def published(bus: FakeBus) -> list[refusals.Refusal]:
    return [d.msg for d in bus.published[registry.REFUSAL.key("drone")]]


@pytest.mark.parametrize("kind", ["mavlink", "tello"])
def test_a_stream_refused_for_the_lease_is_reported_to_its_sender_at_once_then_once_a_second(
    kind,
):
    bus = FakeBus(start=1_700_000_000.0)
    bridge = wired(kind, bus, lease=True)
    apps = FakeNode("apps", bus)
    reply = apps.call(
        registry.COMMAND_LEASE, LeaseRequest(action="take"), attachment=commander_attachment("ada")
    )
    assert reply.granted
    ada = DroneClient(FakeNode("ada", bus), name="ada", inline_calls=True)
    bob = DroneClient(FakeNode("bob", bus), name="bob", inline_calls=True)
    heard: list[tuple[float, refusals.Refusal]] = []
    bob.refusals.listen(lambda r: heard.append((bus.clock.monotonic(), r)))
    started = bus.clock.monotonic()
    stream(bus, bob, EAST, 3.0)
    refused = bridge.core.lease.refused_setpoints
    assert refused >= 3.0 * 30 - 1
    first_at, first = heard[0]
    assert first_at - started <= REPORTED_WITHIN_S
    assert (first.kind, first.commander, first.limit) == ("lease", "bob", "command_lease")
    assert "'ada' holds the command lease" in first.message
    assert 3 <= len(heard) <= 4  # at once, then once a second: not 30 a second
    assert sum(r.count for _, r in heard) <= refused <= sum(r.count for _, r in heard) + 30
    assert ada.refusals.received == 0  # told to bob only
    assert [r.commander for r in published(bus)] == ["bob"] * len(heard)


@pytest.mark.parametrize("kind", ["mavlink", "tello"])
def test_a_setpoint_refused_late_is_reported_to_its_sender_within_a_tenth_of_a_second(kind):
    bus = FakeBus(start=1_700_000_000.0)
    bridge = wired(kind, bus)
    ada = DroneClient(FakeNode("ada", bus), name="ada", inline_calls=True)
    heard: list[tuple[float, refusals.Refusal]] = []
    ada.refusals.listen(lambda r: heard.append((bus.clock.monotonic(), r)))
    stream(bus, ada, HOLD, 2.0)
    assert heard == []
    with bus.held():  # a 1 s cut: the routers hold the stream, then deliver it in a burst
        stream(bus, ada, EAST, 1.0)
    released = bus.clock.monotonic()
    assert bridge.core.setpoint_delay.refused > 0
    at, late = heard[0]
    assert at - released <= REPORTED_WITHIN_S
    assert (late.kind, late.commander, late.limit) == ("late", "ada", "late_setpoint_s")
    assert "later than its usual lag" in late.message
    assert len(heard) <= 2  # the whole burst, one or two messages


@pytest.mark.parametrize("kind", ["mavlink", "tello"])
def test_a_setpoint_outside_the_bridges_envelope_is_reported_naming_the_limit(kind):
    bus = FakeBus(start=1_700_000_000.0)
    bridge = wired(kind, bus)
    ada = DroneClient(FakeNode("ada", bus), name="ada", inline_calls=True)
    started = bus.clock.monotonic()
    stream(bus, ada, FAR, 0.5)
    assert bridge.core.rejected_setpoints >= 15
    (refused,) = list(ada.refusals.recent)
    assert ada.refusals.received_at - started <= REPORTED_WITHIN_S
    assert (refused.kind, refused.limit) == ("envelope", "fence")
    assert "outside the envelope's fence" in refused.message
    wild = PositionTarget(coordinate_frame=FRAME_LOCAL_NED, type_mask=99)
    stream(bus, ada, wild, 0.1)  # another rule: told at once, not held behind the first
    assert ada.refusals.recent[-1].kind == "validation"
    assert ada.refusals.recent[-1].limit == "type_mask"
