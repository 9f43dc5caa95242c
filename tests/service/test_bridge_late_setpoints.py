"""A setpoint held on the way during a cut never flies: both bridges' cores on the fake bus, a
commander's stream held by a stalled link and delivered in a burst (virtual time)."""

from __future__ import annotations

import pytest
from wired_bridge import Wired, wire

from dronewrapper.client import DroneClient
from dronewrapper.msgs import registry
from dronewrapper.msgs.geometry import Vector3
from dronewrapper.msgs.mavros import FRAME_BODY_NED, MASK_VELOCITY, PositionTarget
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
PERIOD = 1 / 30


def wired(kind: str, bus: FakeBus) -> Wired:
    if kind == "mavlink":
        core, module = BridgeCore(MavlinkConfig()), mavlink_node
    else:
        core, module = TelloCore(TelloConfig(video=False)), tello_node
    return wire(core, module, bus)


def stream(bus: FakeBus, commander: DroneClient, target: PositionTarget, seconds: float) -> None:
    """The commander streams ``target`` for ``seconds`` of bus time."""
    commander.set(target, bus.clock.monotonic())
    end = bus.clock.monotonic() + seconds
    while bus.clock.monotonic() < end - 1e-9:
        commander.poll(bus.clock.monotonic())
        bus.clock.advance_to(bus.clock.monotonic() + PERIOD)


@pytest.mark.parametrize("kind", ["mavlink", "tello"])
def test_a_command_withdrawn_during_a_held_cut_never_flies(kind):
    bus = FakeBus(start=1_700_000_000.0)
    bridge = wired(kind, bus)
    commander = DroneClient(FakeNode("app", bus), name="ada", inline_calls=True)
    flown: list[float] = []
    bus.subscribe(  # after the bridge's: sees what each sample left the core flying
        registry.SETPOINT_RAW_LOCAL.key("drone"),
        lambda *_: flown.append(bridge.core.failsafe.target.velocity.x),
    )
    stream(bus, commander, HOLD, 2.0)
    assert flown and set(flown) == {0.0}
    key = registry.SETPOINT_RAW_LOCAL.key("drone")
    before = len(bus.published[key])
    with bus.held():  # a 2 s cut: the routers' stream holds every setpoint
        stream(bus, commander, EAST, 1.0)
        stream(bus, commander, HOLD, 1.0)  # the command withdrawn before the link is back
    delay = bridge.core.setpoint_delay
    assert set(flown) == {0.0}, "a withdrawn command flew"
    held = len(bus.published[key]) - before
    assert held >= round(2.0 / PERIOD) and delay.refused == held  # all of the burst
    stream(bus, commander, HOLD, 1.0)  # the link back: fresh setpoints fly 0.3 s on
    assert held < delay.refused <= held + round(0.3 / PERIOD) + 1 and flown[-1] == 0.0
    assert bridge.core.failsafe.is_fresh(bus.clock.monotonic())


def test_the_late_rule_is_in_both_cores_config():
    assert MavlinkConfig().late_setpoint_s == 0.3 and TelloConfig().late_setpoint_s == 0.3
    with pytest.raises(ValueError, match="late_setpoint_s"):
        MavlinkConfig(late_setpoint_s=0.0)
    with pytest.raises(ValueError, match="late_setpoint_s"):
        TelloConfig(late_setpoint_s=-1.0)
