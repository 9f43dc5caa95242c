"""Both bridges' real ``Bridge`` on the fake bus, time injected through the node alone.

Each bridge is made and started as its process does (``Bridge(node, config, link)``,
``start()``): its threads (MAVLink: receive, stream, link status; Tello: replies, state,
control) are the node clock's, its core starts at that clock and its driver reads it, so on a
:class:`~dronewrapper.runtime.fake.FakeNode` everything runs in the bus's virtual time, nothing
swapped. The link is the simulator's aircraft in process, on the same clock
(tests/clocked_autopilot.py: real MAVLink bytes; tests/clocked_tello.py: the SDK's text). What
is checked is exact in that time, however loaded the machine.
"""

from __future__ import annotations

from collections.abc import Iterator

import pytest
from clocked_autopilot import ClockedAutopilot
from clocked_tello import ClockedTello
from pymavlink.dialects.v20 import common as mavlink

from dronewrapper.msgs import registry
from dronewrapper.msgs.flight import TakeoffRequest
from dronewrapper.msgs.geometry import Vector3
from dronewrapper.msgs.mavros import FRAME_BODY_NED, MASK_VELOCITY, PositionTarget
from dronewrapper.runtime.fake import FakeBus, FakeNode
from dronewrapper_bridge_mavlink.config import Config
from dronewrapper_bridge_mavlink.node import PORTS, Bridge
from dronewrapper_bridge_tello import node as tello_node
from dronewrapper_bridge_tello.config import Config as TelloConfig

T0 = 1_700_000_000.0
"""The bus's start (monotonic and Unix s alike)."""
HOVER = PositionTarget(coordinate_frame=FRAME_BODY_NED, type_mask=MASK_VELOCITY, velocity=Vector3())


class Rig:
    """A bridge (``bridge``, MAVLink unless ``tello``) on ``bus`` facing ``link``, started;
    ``user``: an app's node."""

    def __init__(self, *, tello: bool = False) -> None:
        self.bus = FakeBus(start=T0)
        self.node = FakeNode("bridge", self.bus, ports=tello_node.PORTS if tello else PORTS)
        self.user = FakeNode("apps", self.bus)
        if tello:
            self.tello = ClockedTello(self.node.clock, self.node.stop_event)
            self.bridge = tello_node.Bridge(self.node, TelloConfig(video=False), link=self.tello)
        else:
            self.link = ClockedAutopilot(self.node.clock, self.node.stop_event)
            config = Config(message_rates={}, upload_fence=False)
            self.bridge = Bridge(self.node, config, link=self.link)
        self.threads = self.bridge.start()

    def close(self) -> None:
        self.node.stop()
        for thread in self.threads:
            thread.join(10.0)
        assert not any(thread.is_alive() for thread in self.threads)


@pytest.fixture
def rig() -> Iterator[Rig]:
    made = Rig()
    yield made
    made.close()


@pytest.fixture
def tello() -> Iterator[Rig]:
    made = Rig(tello=True)
    yield made
    made.close()


def test_the_bridge_runs_on_the_node_clock_threads_and_all(rig: Rig):
    clock = rig.bus.clock
    assert rig.bridge.core.now == T0  # the core starts at the node's clock
    clock.run_for(3.5)
    assert rig.bridge.core.connected
    # the link-status thread waits a second of the node's clock between reports, exactly
    statuses = rig.bus.published[registry.LINK_STATUS.key("drone")]
    assert [d.time for d in statuses] == [T0 + 1.0, T0 + 2.0, T0 + 3.0]
    assert all(d.msg.header.stamp == d.time for d in statuses)  # stamped with it too
    # every sample the core published is stamped with the node's clock as it was fed
    for key in (registry.STATE.key("drone"), registry.LOCAL_POSE.key("drone")):
        published = rig.bus.published[key]
        assert published, key
        assert all(T0 <= d.msg.header.stamp <= d.time for d in published), key
    # the receive thread fed the core what the autopilot sent, on the same clock
    assert rig.bridge.core.messages_received > 0
    assert clock.monotonic() == T0 + 3.5


def test_a_take_off_flies_in_virtual_time_through_the_stream_loop(rig: Rig):
    """PX4's take-off needs the bridge's own setpoint stream (the stream thread's ticks)
    primed for ``offboard_prime_s`` before OFFBOARD: the service call waits on the node's
    clock, which moves the bus, and the bridge's threads run meanwhile."""
    clock = rig.bus.clock
    clock.run_for(3.0)  # connected, home known
    asked_at = clock.monotonic()
    result = rig.user.call(registry.FLIGHT_TAKEOFF, TakeoffRequest(height=2.0), timeout=60.0)
    assert result.success, result.message
    flew = clock.monotonic() - asked_at
    assert 1.2 < flew < 30.0  # primed for offboard_prime_s, then the climb
    assert abs(rig.link.autopilot.state.z - 2.0) < 0.15  # ground truth: at the height
    assert rig.link.autopilot.armed and rig.link.autopilot.mode.name == "OFFBOARD"
    sent = [msg.get_type() for _, msg in rig.link.received]
    set_mode = sent.index("COMMAND_LONG", commands(rig, mavlink.MAV_CMD_DO_SET_MODE)[0][0])
    primed = sent[:set_mode].count("SET_POSITION_TARGET_LOCAL_NED")
    assert primed >= 1.2 * 30  # offboard_prime_s of the stream thread's ticks at 30 Hz


def test_a_lost_commander_is_landed_after_its_timeout_of_the_node_clock(rig: Rig):
    """The commander-lost rule runs in the stream thread's ticks: the landing is sent
    ``commander_lost_timeout`` (5 s) after the last setpoint, to the tick (1/30 s)."""
    clock = rig.bus.clock
    clock.run_for(3.0)
    assert rig.user.call(registry.FLIGHT_TAKEOFF, TakeoffRequest(height=2.0)).success
    setpoints = rig.user.publisher(registry.SETPOINT_RAW_LOCAL)
    for _ in range(20):  # a commander streams a hover for a second, then dies
        setpoints.put(HOVER)
        last = clock.monotonic()
        clock.run_for(0.05)
    clock.run_for(6.0)
    landings = commands(rig, mavlink.MAV_CMD_NAV_LAND)
    assert len(landings) == 1
    assert 5.0 <= landings[0][1] - last <= 5.0 + 1 / 30 + 1e-6
    assert rig.link.autopilot.mode.name == "LAND"


def commands(rig: Rig, command: int) -> list[tuple[int, float]]:
    """(index in what the autopilot was sent, clock's time) of each COMMAND_LONG ``command``."""
    return [
        (i, t)
        for i, (t, msg) in enumerate(rig.link.received)
        if msg.get_type() == "COMMAND_LONG" and msg.command == command
    ]


def test_the_tello_bridge_runs_on_the_node_clock_and_takes_off_in_it(tello: Rig):
    clock = tello.bus.clock
    assert tello.bridge.core.now == T0
    clock.run_for(3.0)
    assert tello.bridge.core.connected and tello.bridge.core.sdk_mode
    assert tello.tello.sent[0] == (T0 + 1 / 20, "command")  # the control thread's first tick
    for key in (registry.STATE.key("drone"), registry.LOCAL_POSE.key("drone")):
        published = tello.bus.published[key]
        assert published and all(T0 <= d.msg.header.stamp <= d.time for d in published), key
    asked_at = clock.monotonic()
    result = tello.user.call(registry.FLIGHT_TAKEOFF, TakeoffRequest(height=1.5), timeout=60.0)
    assert result.success, result.message
    assert abs(tello.tello.protocol.flight.state.z - 1.5) < 0.1  # ground truth
    commands = [(t - asked_at, text) for t, text in tello.tello.sent if not text.startswith("rc")]
    assert commands[-2][1] == "takeoff" and commands[-1][1].startswith("up ")  # to 1.5 m
    assert 0.0 <= commands[-2][0] < commands[-1][0] < clock.monotonic() - asked_at < 30.0
