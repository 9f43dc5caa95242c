"""bridge_mavlink against the simulator (a PX4-like autopilot process) over real UDP.

Every test runs the real processes: a Zenoh router (fixture), ``python -m dronewrapper_sim``
and ``python -m dronewrapper_bridge_mavlink`` on free ports, and drives them at key level the
way the SDK does. Waits are bounded and generous (2 shared cores).
"""

from __future__ import annotations

import math
import os
import random
import socket
import sys
import threading
import time
from collections.abc import Iterator
from dataclasses import dataclass

import pytest

os.environ.setdefault("MAVLINK20", "1")

from pymavlink import mavutil

from dronewrapper.msgs import registry
from dronewrapper.msgs.geometry import Point, Vector3
from dronewrapper.msgs.mavros import (
    FRAME_BODY_NED,
    FRAME_LOCAL_NED,
    LANDED_STATE_IN_AIR,
    LANDED_STATE_ON_GROUND,
    MASK_MIXED,
    MASK_POSITION,
    MASK_VELOCITY,
    CommandBool,
    CommandTOL,
    PositionTarget,
    SetMode,
)
from dronewrapper.runtime import Node, ServiceError
from support import client_node, free_port, python_module, wait_for

pytestmark = pytest.mark.integration

COMMANDER = """
import sys, time
from dronewrapper.msgs import registry
from dronewrapper.msgs.mavros import PositionTarget, FRAME_BODY_NED, MASK_MIXED
from dronewrapper.msgs.geometry import Vector3, Point
from dronewrapper.runtime import Node, ZenohOptions
endpoint, vx, z = sys.argv[1], float(sys.argv[2]), float(sys.argv[3])
with Node("commander", ZenohOptions(connect=[endpoint], name="commander")) as node:
    pub = node.publisher(registry.SETPOINT_RAW_LOCAL)
    target = PositionTarget(coordinate_frame=FRAME_BODY_NED, type_mask=MASK_MIXED,
                            velocity=Vector3(x=vx), position=Point(z=z))
    print("commanding", flush=True)
    while node.sleep(0.05):
        pub.put(target)
"""


@dataclass
class Rig:
    """The running processes and the test's own Zenoh node with the telemetry it watches."""

    router: str
    onboard_port: int
    gcs_port: int
    user: Node
    sim: object
    bridge: object

    def __post_init__(self) -> None:
        u = self.user
        self.state = u.latest(registry.STATE)
        self.ext = u.latest(registry.EXTENDED_STATE)
        self.pose = u.latest(registry.LOCAL_POSE)
        self.vbody = u.latest(registry.VELOCITY_BODY)
        self.vlocal = u.latest(registry.VELOCITY_LOCAL)
        self.fix = u.latest(registry.GLOBAL_POSITION)
        self.battery = u.latest(registry.BATTERY)
        self.texts: list = []
        u.subscribe(registry.STATUSTEXT, self.texts.append)
        self.states: list = []
        u.subscribe(registry.STATE, self.states.append)
        self.setpoints = u.publisher(registry.SETPOINT_RAW_LOCAL)
        self._target: PositionTarget | None = None
        self._stop = threading.Event()
        self._streamer = threading.Thread(target=self._stream, daemon=True)
        self._streamer.start()

    # -- a commander inside the test, like the SDK's 20 Hz stream
    def _stream(self) -> None:
        while not self._stop.wait(0.05):
            target = self._target
            if target is not None:
                self.setpoints.put(target)

    def command(self, target: PositionTarget | None) -> None:
        self._target = target
        if target is not None:
            self.setpoints.put(target)

    def close(self) -> None:
        self._stop.set()
        self._streamer.join(2)

    def z(self) -> float:
        return self.pose.value.pose.position.z if self.pose.value else math.nan

    def call(self, service, request, timeout: float = 20.0):
        return self.user.call(service, request, timeout=timeout)

    def hold_here(self) -> PositionTarget:
        p = self.pose.wait(10).pose.position
        return PositionTarget(
            coordinate_frame=FRAME_LOCAL_NED,
            type_mask=MASK_POSITION,
            position=Point(x=p.x, y=p.y, z=p.z),
            yaw=yaw_of(self.pose.value),
        )

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


def yaw_of(pose) -> float:
    q = pose.pose.orientation
    return math.atan2(2 * (q.w * q.z + q.x * q.y), 1 - 2 * (q.y * q.y + q.z * q.z))


def mixed(vx: float, z: float, yaw_rate: float = 0.0) -> PositionTarget:
    return PositionTarget(
        coordinate_frame=FRAME_BODY_NED,
        type_mask=MASK_MIXED,
        velocity=Vector3(x=vx),
        position=Point(z=z),
        yaw_rate=yaw_rate,
    )


def velocity(vx: float = 0.0, vy: float = 0.0, vz: float = 0.0) -> PositionTarget:
    return PositionTarget(
        coordinate_frame=FRAME_BODY_NED, type_mask=MASK_VELOCITY, velocity=Vector3(x=vx, y=vy, z=vz)
    )


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


def count_rate(latest, seconds: float) -> float:
    start = latest.count
    time.sleep(seconds)
    return (latest.count - start) / seconds


def test_dronewrapper_flight_at_key_level(rig):
    # telemetry keys and rates (on the ground)
    rates = {}
    t0 = time.monotonic()
    counts0 = {k: getattr(rig, k).count for k in ("pose", "vbody", "vlocal", "fix", "battery",
                                                   "state", "ext")}  # fmt: skip
    time.sleep(3.0)
    elapsed = time.monotonic() - t0
    for k, c in counts0.items():
        rates[k] = (getattr(rig, k).count - c) / elapsed
    for k in ("pose", "vbody", "vlocal"):
        assert rates[k] >= 30.0, rates
    assert rates["fix"] >= 5.0 and rates["battery"] >= 1.0, rates
    assert rates["state"] >= 1.0 and rates["ext"] >= 2.0, rates
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
    time.sleep(3.0)
    p = rig.pose.value.pose.position
    dx, dy = p.x - x0, p.y - y0
    moved = math.hypot(dx, dy)
    assert moved > 1.0, f"moved only {moved:.2f} m"
    assert math.cos(math.atan2(dy, dx) - yaw) > 0.9, "did not move along the heading"
    assert rig.vbody.value.twist.linear.x > 0.5  # forward in FLU
    assert abs(rig.z() - 3.0) < 0.5

    # land and disarm
    rig.command(None)
    reply = rig.call(registry.LAND, CommandTOL())
    assert reply.success, reply.message
    wait_for(lambda: rig.state.value.mode == "AUTO.LAND", 5, what="AUTO.LAND")
    rig.wait_landed_disarmed()


def test_killed_commander_hover_then_land(rig, spawn):
    rig.take_off_offboard(2.0)
    commander = spawn([sys.executable, "-c", COMMANDER, rig.router, "1.5", "2.0"], "commander")
    wait_for(lambda: "commanding" in commander.output(), 20, what="commander up")
    rig.command(None)  # only the commander process commands now (two would alternate)
    wait_for(lambda: rig.vlocal.value and math.hypot(rig.vlocal.value.twist.linear.x,
             rig.vlocal.value.twist.linear.y) > 0.8, 15, what="commander flies")  # fmt: skip
    heard: list[float] = []
    rig.user.subscribe(registry.SETPOINT_RAW_LOCAL, lambda _m: heard.append(time.time()))
    time.sleep(0.5)
    commander.proc.kill()  # SIGKILL: no goodbye
    killed = time.monotonic()
    commander.proc.wait(5)
    hold = wait_for(
        lambda: next((s for s in rig.states if s.failsafe == "hold"), None), 3, what="hold"
    )
    last_setpoint = heard[-1]
    assert 0.0 < hold.header.stamp - last_setpoint < 0.6, hold.header.stamp - last_setpoint
    # hovering: horizontal velocity decays to near zero
    wait_for(
        lambda: math.hypot(rig.vlocal.value.twist.linear.x, rig.vlocal.value.twist.linear.y) < 0.3,
        4,
        what="hover",
    )
    # commander lost (5 s) -> land; landed and disarmed well within the contract
    wait_for(lambda: rig.state.value.failsafe == "land", 8, what="failsafe land")
    assert time.monotonic() - killed < 5.0 + 1.5
    assert rig.state.value.mode == "AUTO.LAND" or wait_for(
        lambda: rig.state.value.mode == "AUTO.LAND", 3
    )
    rig.wait_landed_disarmed(40)


class LossyRelay:
    """A UDP relay between the sim and the bridge dropping ``loss`` of packets each way."""

    def __init__(self, bridge_port: int, loss: float, seed: int = 42) -> None:
        self.sim_side = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self.sim_side.bind(("127.0.0.1", 0))
        self.port = self.sim_side.getsockname()[1]
        self.bridge_side = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self.bridge_side.bind(("127.0.0.1", 0))
        self.bridge_addr = ("127.0.0.1", bridge_port)
        self.sim_addr = None
        self.loss = loss
        self.rng = random.Random(seed)
        self.dropped = [0, 0]
        self.passed = [0, 0]
        self._stop = threading.Event()
        for sock in (self.sim_side, self.bridge_side):
            sock.settimeout(0.1)
        self._threads = [
            threading.Thread(target=self._pump, args=(0,), daemon=True),
            threading.Thread(target=self._pump, args=(1,), daemon=True),
        ]
        for t in self._threads:
            t.start()

    def _pump(self, direction: int) -> None:
        src = self.sim_side if direction == 0 else self.bridge_side
        while not self._stop.is_set():
            try:
                data, addr = src.recvfrom(65535)
            except TimeoutError:
                continue
            if direction == 0:
                self.sim_addr = addr
            if self.rng.random() < self.loss:
                self.dropped[direction] += 1
                continue
            self.passed[direction] += 1
            if direction == 0:
                self.bridge_side.sendto(data, self.bridge_addr)
            elif self.sim_addr is not None:
                self.sim_side.sendto(data, self.sim_addr)

    def close(self) -> None:
        self._stop.set()
        for t in self._threads:
            t.join(2)
        self.sim_side.close()
        self.bridge_side.close()


def test_lossy_link_arm_takeoff_land(router, spawn):
    bridge_port, gcs = free_port(socket.SOCK_DGRAM), free_port(socket.SOCK_DGRAM)
    relay = LossyRelay(bridge_port, loss=0.2)
    bridge = start_bridge(spawn, router, bridge_port)
    start_sim(spawn, router, relay.port, gcs)
    user = client_node(router, name="test")
    rig = Rig(router, relay.port, gcs, user, None, bridge)
    try:
        wait_for(lambda: rig.state.value and rig.state.value.connected, 30, what="connected")
        wait_for(lambda: rig.pose.value, 10)
        armed = rig.call(registry.ARMING, CommandBool(value=True), timeout=30)
        assert armed.success, armed.message
        # 3.5 m, not the autopilot's default 2.5 m: proves the AMSL conversion of param7
        took_off = rig.call(registry.TAKEOFF, CommandTOL(altitude=3.5), timeout=30)
        assert took_off.success, took_off.message
        wait_for(lambda: rig.z() > 3.2, 25, what="take-off to 3.5 m")
        time.sleep(1.0)
        assert 3.2 < rig.z() < 3.9
        landing = rig.call(registry.LAND, CommandTOL(), timeout=30)
        assert landing.success, landing.message
        rig.wait_landed_disarmed(40)
        # the link really was lossy, both ways (the bridge -> sim way carries little traffic)
        down = relay.dropped[0] / (relay.dropped[0] + relay.passed[0])
        assert 0.15 < down < 0.25 and relay.dropped[1] >= 2, (relay.dropped, relay.passed)
    finally:
        rig.close()
        user.close()
        relay.close()
        assert bridge.stop() == 0


def test_ground_station_mode_switch_not_fought(rig):
    rig.take_off_offboard(2.0)
    gcs = mavutil.mavlink_connection(
        f"udpin:127.0.0.1:{rig.gcs_port}", source_system=254, source_component=190
    )
    try:
        hb = gcs.recv_match(type="HEARTBEAT", blocking=True, timeout=10)
        assert hb is not None, "no heartbeat on the GCS link"
        main, sub = 4, 3  # AUTO.LOITER
        for _ in range(3):
            gcs.mav.command_long_send(hb.get_srcSystem(), 1, 176, 0, 1, main, sub, 0, 0, 0, 0)
            if gcs.recv_match(type="COMMAND_ACK", blocking=True, timeout=2):
                break
        wait_for(lambda: rig.state.value.mode == "AUTO.LOITER", 5, what="pilot's AUTO.LOITER")
        wait_for(lambda: any("not switching back" in t.text for t in rig.texts), 5, what="report")
        # the SDK keeps streaming; the bridge must not switch back, nor land on its own
        rig.command(mixed(0.5, 2.0))
        since = len(rig.states)
        time.sleep(5.5)  # longer than commander_lost_timeout
        assert rig.state.value.mode == "AUTO.LOITER" and rig.state.value.armed
        after = rig.states[since:]
        assert len(after) >= 6 and all(s.mode == "AUTO.LOITER" for s in after)
        assert rig.state.value.failsafe in ("", "hold") and rig.z() > 1.4
    finally:
        gcs.close()
    rig.command(None)
    assert rig.call(registry.LAND, CommandTOL()).success
    rig.wait_landed_disarmed(40)


def test_sim_restart_reconnects(rig, spawn):
    wait_for(lambda: rig.pose.value, 10)
    assert rig.sim.stop() == 0
    gone = time.monotonic()
    wait_for(lambda: not rig.state.value.connected, 8, what="disconnected")
    assert time.monotonic() - gone < 3.0 + 2.0
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
        rig.call(registry.TAKEOFF, CommandTOL(altitude=-3.0))
    wait_for(lambda: "setpoint refused" in rig.bridge.output(), 5, what="refusal logged")
    time.sleep(1.0)
    after = rig.state.value
    assert rig.bridge.alive() and after.connected
    assert (after.mode, after.armed, after.failsafe) == (before.mode, before.armed, "")
    assert abs(rig.z()) < 0.3  # nothing moved the vehicle
