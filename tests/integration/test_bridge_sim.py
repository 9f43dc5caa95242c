"""bridge_mavlink against the simulator (a PX4-like autopilot process) over real UDP.

Every test runs the real processes: a Zenoh router (fixture), ``python -m dronewrapper_sim``
and ``python -m dronewrapper_bridge_mavlink`` on free ports, and drives them at key level the
way the SDK does: what only real processes show (MAVLink over real UDP sockets, the telemetry
rates, a restarted simulator). The bridge's failsafes after a commander dies, a lossy link and
a ground station's mode switch are held in virtual time by
tests/service/test_mavlink_flight_virtual.py. Waits are bounded and generous (2 shared cores).
"""

from __future__ import annotations

import itertools
import math
import os
import socket
import time
from collections.abc import Iterator
from dataclasses import dataclass

import pytest

os.environ.setdefault("MAVLINK20", "1")

from bridge_user import BridgeUser
from setpoint_stream import yaw_of
from targets import mixed, position, velocity

from dronewrapper.msgs import registry
from dronewrapper.msgs.mavros import (
    LANDED_STATE_IN_AIR,
    LANDED_STATE_ON_GROUND,
    CommandBool,
    CommandTOL,
    PositionTarget,
    SetMode,
)
from dronewrapper.runtime import Node, ServiceError
from support import client_node, free_port, python_module, wait_for

pytestmark = pytest.mark.integration


@dataclass
class Rig(BridgeUser):
    """The running processes and the test's own Zenoh node with the telemetry it watches."""

    router: str
    onboard_port: int
    gcs_port: int
    user: Node
    sim: object
    bridge: object

    def __post_init__(self) -> None:
        super().__post_init__()
        self.vlocal = self.user.latest(registry.VELOCITY_LOCAL)
        self.fix = self.user.latest(registry.GLOBAL_POSITION)
        self.texts: list = []
        self.user.subscribe(registry.STATUSTEXT, self.texts.append)

    def z(self) -> float:
        return self.pose.value.pose.position.z if self.pose.value else math.nan

    def call(self, service, request, timeout: float = 20.0):
        return self.user.call(service, request, timeout=timeout)

    def hold_here(self) -> PositionTarget:
        p = self.pose.wait(10).pose.position
        return position(p.x, p.y, p.z, yaw_of(self.pose.value))

    def take_off_offboard(self, height: float = 3.0) -> None:
        """The SDK's PX4 take-off: hold stream -> OFFBOARD -> arm -> mixed climb."""
        wait_for(lambda: self.state.value and self.state.value.connected, 20, what="connected")
        wait_for(lambda: self.pose.value, 10, what="local pose")
        self.command(self.hold_here())
        time.sleep(1.2)
        assert self.call(registry.SET_MODE, SetMode(custom_mode="OFFBOARD")).mode_sent
        armed = self.call(registry.ARMING, CommandBool(value=True))
        assert armed.success, armed.message
        self.command(mixed(0.0, height))
        wait_for(lambda: self.z() > height - 0.3, 25, what=f"climb to {height} m")

    def wait_landed_disarmed(self, timeout: float = 40.0) -> None:
        wait_for(
            lambda: self.state.value and not self.state.value.armed,
            timeout,
            what="landed and disarmed",
        )
        assert self.ext.value.landed_state == LANDED_STATE_ON_GROUND
        assert self.z() < 0.3


def start_sim(spawn, router: str, onboard_port: int, gcs_port: int, name: str = "sim"):
    return spawn(
        python_module(
            "dronewrapper_sim",
            "--scenario", "empty", "--no-cameras",
            "--udp-onboard", f"{onboard_port}:0", "--udp-gcs", f"{gcs_port}:0",
            "--connect", router, "--name", name,
        ),
        name,
    )  # fmt: skip


def start_bridge(spawn, router: str, listen_port: int, *extra: str):
    return spawn(
        python_module(
            "dronewrapper_bridge_mavlink",
            "--connect", router,
            "--connection", f"udpin:127.0.0.1:{listen_port}",
            *extra,
        ),
        "bridge",
    )  # fmt: skip


@pytest.fixture
def rig(router, spawn) -> Iterator[Rig]:
    onboard, gcs = free_port(socket.SOCK_DGRAM), free_port(socket.SOCK_DGRAM)
    bridge = start_bridge(spawn, router, onboard)
    sim = start_sim(spawn, router, onboard, gcs)
    user = client_node(router, name="test")
    r = Rig(router, onboard, gcs, user, sim, bridge)
    try:
        wait_for(lambda: r.state.value and r.state.value.connected, 30, what="bridge connected")
        yield r
    finally:
        r.close()
        user.close()
        assert bridge.stop() == 0, bridge.output()[-2000:]


def median_period(msgs: list) -> float:
    """The median interval (s) between the header stamps of ``msgs``: a rate measured on the
    publisher's clock, which a stalled test process or a short stall upstream cannot skew."""
    gaps = sorted(b.header.stamp - a.header.stamp for a, b in itertools.pairwise(msgs))
    return gaps[len(gaps) // 2]


# topic -> (samples to collect, longest median period in s): at least 60 % of the bridge's rates
# (pose and velocities 50 Hz, fix 10 Hz, battery and state 2 Hz, extended state 4 Hz)
TELEMETRY_RATES = {
    registry.LOCAL_POSE: (60, 1 / 30),
    registry.VELOCITY_BODY: (60, 1 / 30),
    registry.VELOCITY_LOCAL: (60, 1 / 30),
    registry.GLOBAL_POSITION: (12, 1 / 5),
    registry.BATTERY: (5, 1 / 1),
    registry.STATE: (5, 1 / 1),
    registry.EXTENDED_STATE: (8, 1 / 2),
}


def test_dronewrapper_flight_at_key_level(rig):
    # telemetry keys and rates (on the ground)
    heard: dict = {topic: [] for topic in TELEMETRY_RATES}
    for topic, samples in heard.items():
        rig.user.subscribe(topic, samples.append)
    wait_for(
        lambda: all(len(heard[t]) >= n for t, (n, _) in TELEMETRY_RATES.items()),
        30,
        what="telemetry on every key",
    )
    for topic, (_, longest) in TELEMETRY_RATES.items():
        assert median_period(heard[topic]) <= longest, (topic.template, median_period(heard[topic]))
    assert 0.0 < rig.battery.value.percentage <= 1.0
    assert rig.state.value.autopilot == "px4"
    assert rig.ext.value.landed_state == LANDED_STATE_ON_GROUND

    rig.take_off_offboard(3.0)
    assert rig.state.value.mode == "OFFBOARD" and rig.state.value.armed
    wait_for(lambda: rig.ext.value.landed_state == LANDED_STATE_IN_AIR, 10, what="in air")

    # body velocity: forward at the current heading
    yaw = yaw_of(rig.pose.value)
    start = rig.pose.value.pose.position
    x0, y0 = start.x, start.y
    rig.command(mixed(1.0, 3.0))

    def moved() -> float:
        p = rig.pose.value.pose.position
        return math.hypot(p.x - x0, p.y - y0)

    wait_for(lambda: moved() > 1.5, 15, what="fly 1.5 m forward")
    p = rig.pose.value.pose.position
    assert math.cos(math.atan2(p.y - y0, p.x - x0) - yaw) > 0.9, "did not move along the heading"
    assert rig.vbody.value.twist.linear.x > 0.5  # forward in FLU
    assert abs(rig.z() - 3.0) < 0.5

    # land and disarm
    rig.command(None)
    reply = rig.call(registry.LAND, CommandTOL.land())
    assert reply.success, reply.message
    wait_for(lambda: rig.state.value.mode == "AUTO.LAND", 10, what="AUTO.LAND")
    rig.wait_landed_disarmed()


def test_sim_restart_reconnects(rig, spawn):
    wait_for(lambda: rig.pose.value, 10)
    assert rig.sim.stop() == 0
    gone = time.time()
    lost = wait_for(
        lambda: next((s for s in rig.states if not s.connected and s.header.stamp > gone), None),
        15,
        what="disconnected",
    )
    # heartbeat timeout 3 s after the last heartbeat (which came before `gone`), judged on the
    # bridge's stamp; the margin covers its 30 Hz tick and a loaded machine
    assert lost.header.stamp - gone < 3.0 + 2.0
    poses_before = rig.pose.count
    start_sim(spawn, rig.router, rig.onboard_port, rig.gcs_port, name="sim2")
    wait_for(lambda: rig.state.value.connected, 30, what="reconnected")
    wait_for(lambda: rig.pose.count > poses_before + 30, 10, what="telemetry resumed")
    reply = rig.call(registry.SET_MODE, SetMode(custom_mode="AUTO.LOITER"))
    assert reply.mode_sent, reply.message


def test_bad_input_refused_and_nothing_changes(rig):
    """NaN / out-of-range setpoints, garbage bytes, unknown modes: refused, the bridge lives on."""
    wait_for(lambda: rig.pose.value, 10)
    before = rig.state.value
    for bad in (velocity(vx=math.nan), velocity(vz=math.inf), velocity(vx=1e3), mixed(0.0, -1e6)):
        rig.setpoints.put(bad)
    rig.user.session.put(registry.SETPOINT_RAW_LOCAL.key("drone"), b"\xff\x00not msgpack")
    with pytest.raises(ServiceError, match="valid modes"):
        rig.call(registry.SET_MODE, SetMode(custom_mode="FLY_AWAY"))
    with pytest.raises(ServiceError, match="altitude"):
        rig.call(registry.TAKEOFF, CommandTOL.takeoff(-3.0))
    wait_for(lambda: "setpoint refused" in rig.bridge.output(), 15, what="refusal logged")
    time.sleep(1.0)
    after = rig.state.value
    assert rig.bridge.alive() and after.connected
    assert (after.mode, after.armed, after.failsafe) == (before.mode, before.armed, "")
    assert abs(rig.z()) < 0.3  # nothing moved the vehicle
