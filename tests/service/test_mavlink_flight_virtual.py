"""bridge_mavlink's failsafes and lossy-link flight against the simulator's autopilot in
virtual time.

The real ``Bridge`` (its receive, stream and link-status threads) runs on a fake bus, its link
the simulator's PX4-like autopilot in process on the node's clock (tests/clocked_autopilot.py:
real MAVLink bytes both ways). A test drives it at key level as the SDK does, its commander's
20 Hz stream a worker of the same clock (tests/clocked_setpoints.py); every stamp is that
clock's, exact however loaded the machine. The real UDP path, a real process restart and the
telemetry rates stay in tests/integration/test_bridge_sim.py.
"""

from __future__ import annotations

import math
import random
from collections.abc import Iterator

import pytest
from clocked_autopilot import ClockedAutopilot
from pymavlink.dialects.v20 import common as mavlink
from targets import mixed, position
from virtual_bridge import VirtualBridge

from dronewrapper import CommandRefused
from dronewrapper.msgs import registry
from dronewrapper.msgs.flight import TakeoffRequest
from dronewrapper.msgs.mavros import (
    LANDED_STATE_ON_GROUND,
    CommandBool,
    CommandTOL,
    PositionTarget,
    SetMode,
)
from dronewrapper_bridge_mavlink.config import Config
from dronewrapper_bridge_mavlink.node import Bridge


def yaw_of(pose) -> float:
    q = pose.pose.orientation
    return math.atan2(2.0 * (q.w * q.z + q.x * q.y), 1.0 - 2.0 * (q.y * q.y + q.z * q.z))


def horizontal_speed(twist_stamped) -> float:
    return math.hypot(twist_stamped.twist.linear.x, twist_stamped.twist.linear.y)


class LossyParser:
    """One end's MAVLink parser losing ``loss`` of the packets it is handed (seeded): a lost
    one never reaches the parser, as a datagram lost on the way."""

    def __init__(self, inner, loss: float, seed: int) -> None:
        self.inner, self.loss, self.rng = inner, loss, random.Random(seed)
        self.dropped = self.passed = 0

    def parse_buffer(self, data: bytes):
        if self.rng.random() < self.loss:
            self.dropped += 1
            return []
        self.passed += 1
        return self.inner.parse_buffer(data)


class Rig(VirtualBridge):
    """A started MAVLink bridge on a fake bus facing the clocked autopilot (``link``;
    tests/virtual_bridge.py), the app's node also keeping the local velocity and the
    STATUSTEXTs."""

    def __init__(self, loss: float = 0.0, ground_station: bool = False) -> None:
        super().__init__()
        self.link = ClockedAutopilot(
            self.node.clock, self.node.stop_event, ground_station=ground_station
        )
        if loss:  # one generator per direction, as a lossy relay's: sim->bridge, bridge->sim
            self.link._at_bridge = LossyParser(self.link._at_bridge, loss, seed=42)
            self.link._at_autopilot = LossyParser(self.link._at_autopilot, loss, seed=43)
        self.vlocal = self.user.latest(registry.VELOCITY_LOCAL)
        self.texts: list = []
        self.user.subscribe(registry.STATUSTEXT, self.texts.append)
        self.start(Bridge(self.node, Config(message_rates={}, upload_fence=False), self.link))

    def z(self) -> float:
        return self.pose.value.pose.position.z if self.pose.value else math.nan

    def hold_here(self) -> PositionTarget:
        p = self.pose.value.pose.position
        return position(p.x, p.y, p.z, yaw_of(self.pose.value))

    def take_off_offboard(self, height: float) -> None:
        """The SDK's PX4 take-off: hold stream -> OFFBOARD -> arm -> mixed climb."""
        self.wait_for(lambda: self.state.value and self.state.value.connected, 20, "connected")
        self.wait_for(lambda: self.pose.value, 10, "local pose")
        self.command(self.hold_here())
        self.clock.run_for(1.2)
        assert self.call(registry.SET_MODE, SetMode(custom_mode="OFFBOARD")).mode_sent
        armed = self.call(registry.ARMING, CommandBool(value=True))
        assert armed.success, armed.message
        self.command(mixed(0.0, height))
        self.wait_for(lambda: self.z() > height - 0.3, 25, f"climb to {height} m")

    def wait_landed_disarmed(self, timeout: float) -> None:
        self.wait_for(
            lambda: self.state.value and not self.state.value.armed, timeout, "landed, disarmed"
        )
        assert self.ext.value.landed_state == LANDED_STATE_ON_GROUND
        assert self.z() < 0.3


@pytest.fixture
def rig() -> Iterator[Rig]:
    made = Rig()
    yield made
    made.close()


def test_killed_commander_hover_then_land(rig: Rig):
    """Judged on the clock's stamps: the commander stamps each setpoint when it sends it, the
    bridge stamps State and velocities when it publishes them."""
    rig.take_off_offboard(2.0)
    rig.command(mixed(1.5, 2.0))
    rig.wait_for(lambda: rig.vlocal.value and horizontal_speed(rig.vlocal.value) > 0.8, 20, "flies")
    sent: list[float] = []
    rig.user.subscribe(registry.SETPOINT_RAW_LOCAL, lambda m: sent.append(m.header.stamp))
    velocities: list = []
    rig.user.subscribe(registry.VELOCITY_LOCAL, velocities.append)
    rig.wait_for(lambda: len(sent) >= 5, 10, "the commander's setpoints")
    rig.command(None)  # the commander dies: no goodbye

    def first_state(failsafe: str, after: float):
        return next((s for s in rig.states if s.failsafe == failsafe and s.header.stamp > after),
                    None)  # fmt: skip

    last_setpoint = max(sent)
    assert last_setpoint == rig.stream.sent[-1]
    # setpoint_timeout 0.5 s -> hold: never before, and within the bridge's 30 Hz tick (the
    # real-process test allowed up to 1.5 s for delivery on a loaded machine)
    hold = rig.wait_for(lambda: first_state("hold", last_setpoint), 10, "failsafe hold")
    silence = hold.header.stamp - last_setpoint
    assert 0.5 <= silence < 0.5 + 2 / 30 + 1e-6, f"hold {silence:.3f} s after the last setpoint"
    # commander_lost_timeout 5 s -> land
    land = rig.wait_for(lambda: first_state("land", last_setpoint), 15, "failsafe land")
    silence = land.header.stamp - last_setpoint
    assert 5.0 <= silence < 5.0 + 2 / 30 + 1e-6, f"land {silence:.3f} s after the last setpoint"
    # hovering in between: the horizontal velocity decayed to near zero before the landing
    hovering = [
        v
        for v in velocities
        if hold.header.stamp < v.header.stamp < land.header.stamp and horizontal_speed(v) < 0.3
    ]
    assert hovering, "still moving when the bridge decided to land"
    rig.wait_for(lambda: rig.state.value.mode == "AUTO.LAND", 10, "AUTO.LAND")
    rig.wait_landed_disarmed(40)


def test_lossy_link_arm_takeoff_land():
    rig = Rig(loss=0.2)
    try:
        rig.wait_for(lambda: rig.state.value and rig.state.value.connected, 30, "connected")
        rig.wait_for(lambda: rig.pose.value, 10, "local pose")
        armed = rig.call(registry.ARMING, CommandBool(value=True))
        assert armed.success, armed.message
        # 3.5 m, not the autopilot's default 2.5 m: proves the AMSL conversion of param7
        took_off = rig.call(registry.TAKEOFF, CommandTOL.takeoff(3.5))
        assert took_off.success, took_off.message
        rig.wait_for(lambda: rig.z() > 3.2, 25, "take-off to 3.5 m")
        rig.clock.run_for(1.0)
        assert 3.2 < rig.z() < 3.9
        assert 3.2 < rig.link.autopilot.state.z < 3.9  # ground truth agrees
        landing = rig.call(registry.LAND, CommandTOL.land())
        assert landing.success, landing.message
        rig.wait_landed_disarmed(40)
        # the link really was lossy, both ways (the bridge -> sim way carries little traffic)
        down, up = rig.link._at_bridge, rig.link._at_autopilot
        fraction = down.dropped / (down.dropped + down.passed)
        assert 0.15 < fraction < 0.25 and up.dropped >= 2, (down.dropped, up.dropped)
    finally:
        rig.close()


def test_ground_station_mode_switch_not_fought():
    rig = Rig(ground_station=True)
    try:
        rig.take_off_offboard(2.0)
        gcs = mavlink.MAVLink(None, srcSystem=254, srcComponent=190)
        main, sub = 4, 3  # AUTO.LOITER
        switch = gcs.command_long_encode(
            1, 1, mavlink.MAV_CMD_DO_SET_MODE, 0, 1, main, sub, 0, 0, 0, 0
        )
        switch.pack(gcs)
        replies = rig.link.from_ground_station(switch)
        assert any(m.get_type() == "COMMAND_ACK" for m in replies), replies
        rig.wait_for(lambda: rig.state.value.mode == "AUTO.LOITER", 10, "pilot's AUTO.LOITER")
        rig.wait_for(lambda: any("not switching back" in t.text for t in rig.texts), 10, "report")
        # the SDK keeps streaming; the bridge must not switch back, nor land on its own
        rig.command(mixed(0.5, 2.0))
        since = len(rig.states)
        rig.clock.run_for(5.5)  # longer than commander_lost_timeout
        assert rig.state.value.mode == "AUTO.LOITER" and rig.state.value.armed
        after = rig.states[since:]  # State is periodic (2 Hz): about 11 in that time
        assert len(after) >= 4 and all(s.mode == "AUTO.LOITER" for s in after)
        assert rig.state.value.failsafe in ("", "hold") and rig.z() > 1.4
        assert rig.link.autopilot.mode.name == "LOITER"  # ground truth: still the pilot's mode
        rig.command(None)
        assert rig.call(registry.LAND, CommandTOL.land()).success
        rig.wait_landed_disarmed(40)
    finally:
        rig.close()


def gcs_set_mode(rig: Rig, main_sub: tuple[int, int]) -> None:
    """DO_SET_MODE from a ground station on the autopilot's GCS link, acknowledged."""
    gcs = mavlink.MAVLink(None, srcSystem=254, srcComponent=190)
    switch = gcs.command_long_encode(1, 1, mavlink.MAV_CMD_DO_SET_MODE, 0, 1, *main_sub, 0, 0, 0, 0)
    switch.pack(gcs)
    replies = rig.link.from_ground_station(switch)
    assert any(m.get_type() == "COMMAND_ACK" for m in replies), replies


def test_ground_station_hands_offboard_back_then_the_app_dies_bridge_lands():
    """Before: the bridge stayed 'overridden' and PX4's own offboard-loss failsafe flew RTL.
    The app takes off as the SDK does (the bridge's take-off operation) and hovers streaming
    its position; a ground station switches to AUTO.LOITER and back to OFFBOARD; then the app
    dies. The mode switches on the GCS link over real UDP stay in
    tests/integration/test_sim_mavlink.py."""
    rig = Rig(ground_station=True)
    try:
        rig.clock.run_for(3.0)  # connected, home known
        result = rig.user.call(registry.FLIGHT_TAKEOFF, TakeoffRequest(height=1.5), timeout=60.0)
        assert result.success, result.message
        rig.command(rig.hold_here())  # the app hovers, streaming
        gcs_set_mode(rig, (4, 3))  # AUTO.LOITER
        rig.wait_for(lambda: rig.state.value.mode == "AUTO.LOITER", 10, "GCS AUTO.LOITER")
        rig.wait_for(lambda: any("not switching back" in t.text for t in rig.texts), 10, "report")
        gcs_set_mode(rig, (6, 0))  # OFFBOARD
        rig.wait_for(lambda: rig.state.value.mode == "OFFBOARD", 10, "OFFBOARD again")
        since = len(rig.states)
        heights: list[float] = []
        rig.user.subscribe(registry.LOCAL_POSE, lambda m: heights.append(m.pose.position.z))
        rig.command(None)  # the app dies
        died = rig.clock.monotonic()

        def landing() -> bool:
            state = rig.state.value
            return state.failsafe == "land" and state.mode == "AUTO.LAND"

        rig.wait_for(landing, 25, "commander-lost land in AUTO.LAND")
        after = rig.states[since:]
        assert "hold" in [s.failsafe for s in after]  # held first, then landed
        assert all(s.mode != "AUTO.RTL" for s in after), [s.mode for s in after]
        assert 4.0 < rig.clock.monotonic() - died < 25.0
        rig.wait_landed_disarmed(60)
        assert max(heights) < 2.2, max(heights)  # RTL would have climbed
        assert max(z for _, (_, _, z), _ in rig.link.truth) < 2.2  # ground truth agrees
    finally:
        rig.close()


def test_refused_mode_reaches_set_mode_with_px4s_reason(rig: Rig):
    """The autopilot answers DO_SET_MODE as PX4 does (ACCEPTED from its MAVLink receiver,
    then the commander's TEMPORARILY_REJECTED with its text for a mode that needs RC): the
    bridge's set_mode answers the refusal with PX4's reason, which the SDK raises as
    CommandRefused (that raise over a real router: tests/integration/test_bridge_mode_acks.py)."""
    rig.clock.run_for(3.0)  # connected, home known
    result = rig.user.call(registry.FLIGHT_TAKEOFF, TakeoffRequest(height=1.5), timeout=60.0)
    assert result.success, result.message
    assert rig.state.value.mode == "OFFBOARD"
    for mode, name in (("POSCTL", "Position"), ("ALTCTL", "Altitude")):
        started = rig.clock.monotonic()
        reply = rig.call(registry.SET_MODE, SetMode(custom_mode=mode))
        took = rig.clock.monotonic() - started
        assert not reply.mode_sent
        refused = str(CommandRefused(f"set_mode {mode}", reply.message, reply.result))  # as the SDK
        assert "TEMPORARILY_REJECTED" in refused
        assert f"Switching to {name} is currently not available" in refused
        rig.clock.run_for(0.5)  # the next State
        assert rig.state.value.mode == "OFFBOARD" and rig.state.value.armed
        assert rig.link.autopilot.mode.name == "OFFBOARD"  # ground truth
        rig.clock.run_for(max(0.0, 1.1 - took - 0.5))  # PX4 repeats a refusal's text at most 1/s
    assert rig.call(registry.LAND, CommandTOL.land()).success
    rig.wait_landed_disarmed(60)
