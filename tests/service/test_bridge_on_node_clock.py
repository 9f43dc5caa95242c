"""bridge_mavlink's real ``Bridge`` on the fake bus, time injected through the node alone.

The bridge is made and started as its process does (``Bridge(node, config, link)``,
``start()``): its receive, stream and link-status threads are the node clock's, its core starts
at that clock and its driver reads it, so on a :class:`~dronewrapper.runtime.fake.FakeNode`
everything runs in the bus's virtual time, nothing swapped. The link is the simulator's
autopilot in process (tests/clocked_autopilot.py: real MAVLink bytes, physics on the same
clock). What is checked is exact in that time, however loaded the machine.
"""

from __future__ import annotations

from collections.abc import Iterator

import pytest
from clocked_autopilot import ClockedAutopilot
from pymavlink.dialects.v20 import common as mavlink

from dronewrapper.msgs import registry
from dronewrapper.msgs.flight import TakeoffRequest
from dronewrapper.runtime.fake import FakeBus, FakeNode
from dronewrapper_bridge_mavlink.config import Config
from dronewrapper_bridge_mavlink.node import Bridge

T0 = 1_700_000_000.0
"""The bus's start (monotonic and Unix s alike)."""


class Rig:
    """The bridge (``bridge``) on ``bus`` facing ``link``; ``user``: an app's node."""

    def __init__(self) -> None:
        self.bus = FakeBus(start=T0)
        self.node = FakeNode("bridge_mavlink", self.bus)
        self.link = ClockedAutopilot(self.node.clock, self.node.stop_event)
        config = Config(message_rates={}, upload_fence=False)
        self.bridge = Bridge(self.node, config, link=self.link)
        self.user = FakeNode("apps", self.bus)
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


def test_the_bridge_runs_on_the_node_clock_threads_and_all(rig: Rig):
    clock = rig.bus.clock
    assert rig.bridge.core.now == T0  # the core starts at the node's clock
    clock.run_for(3.5)
    assert rig.bridge.connected
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
    assert rig.bridge.messages_received > 0
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
    sent = [msg.get_type() for msg in rig.link.received]
    set_mode = next(
        i
        for i, msg in enumerate(rig.link.received)
        if sent[i] == "COMMAND_LONG" and msg.command == mavlink.MAV_CMD_DO_SET_MODE
    )
    primed = sent[:set_mode].count("SET_POSITION_TARGET_LOCAL_NED")
    assert primed >= 1.2 * 30  # offboard_prime_s of the stream thread's ticks at 30 Hz
