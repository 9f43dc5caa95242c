"""bridge_tello against the simulated Tello over real UDP, judged from the sim's ground truth.

Every test runs the real processes: a Zenoh router (fixture), ``python -m dronewrapper_sim
--aircraft tello`` on its own loopback address, and ``python -m dronewrapper_bridge_tello``
bound to the same address, and drives the bridge at key level the way the SDK does. Directions
are judged in the sim's true ENU frame (``{ns}/sim/ground_truth``), not in the bridge's
dead-reckoned estimate. Waits are bounded and generous (2 shared cores).
"""

from __future__ import annotations

import math
import random
import signal
import socket
import threading
import time
from collections.abc import Iterator
from dataclasses import dataclass

import numpy as np
import pytest
from bridge_user import BridgeUser
from setpoint_stream import yaw_of

from dronewrapper.msgs import registry
from dronewrapper.msgs.geometry import Point, Vector3
from dronewrapper.msgs.mavros import (
    FRAME_BODY_NED,
    FRAME_LOCAL_NED,
    LANDED_STATE_IN_AIR,
    LANDED_STATE_ON_GROUND,
    MASK_POSITION,
    MASK_VELOCITY,
    CommandBool,
    CommandTOL,
    ParamGet,
    PositionTarget,
    SetMode,
)
from dronewrapper.runtime import Node, ServiceError
from support import client_node, python_module, wait_for

pytestmark = pytest.mark.integration


def loopback_address() -> str:
    """A loopback address of our own, so 8889/8890/11111 never clash with another test."""
    return f"127.{random.randint(10, 250)}.{random.randint(0, 255)}.{random.randint(2, 250)}"


def velocity(vx=0.0, vy=0.0, vz=0.0, yaw_rate=0.0) -> PositionTarget:
    return PositionTarget(
        coordinate_frame=FRAME_BODY_NED,
        type_mask=MASK_VELOCITY,
        velocity=Vector3(x=vx, y=vy, z=vz),
        yaw_rate=yaw_rate,
    )


@dataclass
class Rig(BridgeUser):
    """The processes, and the test's own node with what it watches and a 20 Hz commander."""

    router: str
    address: str
    user: Node
    sim: object
    bridge: object

    def __post_init__(self) -> None:
        super().__post_init__()
        self.truth = self.user.latest(registry.SIM_GROUND_TRUTH)

    def call(self, service, request, timeout: float = 40.0):
        return self.user.call(service, request, timeout=timeout)

    def true_xyz(self) -> np.ndarray:
        p = self.truth.wait(10).pose.position
        return np.array([p.x, p.y, p.z])

    def true_yaw(self) -> float:
        return yaw_of(self.truth.wait(10))

    def take_off(self, height: float = 1.2) -> None:
        reply = self.call(registry.TAKEOFF, CommandTOL.takeoff(height))
        assert reply.success, reply.message
        assert self.true_xyz()[2] == pytest.approx(height, abs=0.15), reply.message
        wait_for(
            lambda: self.ext.value and self.ext.value.landed_state == LANDED_STATE_IN_AIR,
            5,
            what="landed_state IN_AIR",
        )

    def fly(self, target: PositionTarget, seconds: float) -> np.ndarray:
        """Command ``target`` for ``seconds``; returns the true displacement in the body axes
        (forward, left, up) of the heading at the start, m."""
        self.command(velocity())  # from a standstill: the last move's momentum is not judged
        time.sleep(1.0)
        start, yaw = self.true_xyz(), self.true_yaw()
        self.command(target)
        time.sleep(seconds)
        self.command(None)
        moved = self.true_xyz() - start
        c, s = math.cos(yaw), math.sin(yaw)
        return np.array([c * moved[0] + s * moved[1], -s * moved[0] + c * moved[1], moved[2]])

    def speed(self, window: float = 0.3) -> float:
        """True horizontal+vertical speed over ``window`` s (m/s)."""
        a = self.true_xyz()
        time.sleep(window)
        return float(np.linalg.norm(self.true_xyz() - a) / window)

    def wait_landed(self, timeout: float = 40.0) -> None:
        wait_for(lambda: self.true_xyz()[2] < 0.05, timeout, what="on the ground (truth)")
        wait_for(
            lambda: self.ext.value and self.ext.value.landed_state == LANDED_STATE_ON_GROUND,
            10,
            what="landed_state ON_GROUND",
        )
        wait_for(lambda: self.state.value and not self.state.value.armed, 5, what="disarmed")


AUTO_LAND_S = 8.0
"""The simulated Tello's auto-land timeout in the tests that wait for it (the real drone's 15 s
is the default): a keep-alive every ``keepalive_s`` (3 s) must still beat it."""


def start_sim(spawn, router: str, address: str, auto_land_s: float | None = None):
    """The simulated Tello on ``address``; ``auto_land_s`` shortens its 15 s auto-land."""
    extra = ["--set", f"tello.auto_land_s={auto_land_s}"] if auto_land_s else []
    return spawn(
        python_module(
            "dronewrapper_sim", "--aircraft", "tello", "--scenario", "empty",
            "--address", address, "--connect", router, "--name", "sim", *extra,
        ),
        "sim",
    )  # fmt: skip


def start_bridge(spawn, router: str, tello: str, local: str, *extra: str):
    return spawn(
        python_module(
            "dronewrapper_bridge_tello", "--connect", router,
            "--tello", tello, "--local", local, *extra,
        ),
        "bridge",
    )  # fmt: skip


def make_rig(
    router, spawn, *bridge_args: str, tello: str | None = None, auto_land_s: float | None = None
) -> Rig:
    address = loopback_address()
    sim = start_sim(spawn, router, address, auto_land_s)
    bridge = start_bridge(spawn, router, tello or address, address, *bridge_args)
    user = client_node(router, name="test")
    rig = Rig(router, address, user, sim, bridge)
    try:
        wait_for(
            lambda: rig.state.value and rig.state.value.connected and rig.state.value.guided,
            40,
            what=f"bridge connected and in SDK mode\n{bridge.output()[-2000:]}",
        )
        wait_for(lambda: rig.truth.value, 10, what="ground truth")
    except BaseException:
        rig.close()
        user.close()
        raise
    return rig


@pytest.fixture
def rig(router, spawn) -> Iterator[Rig]:
    r = make_rig(router, spawn, "--set", "video=false")
    yield r
    r.close()
    r.user.close()


def test_state_and_services_honestly_mapped(rig):
    s = rig.state.value
    assert s.autopilot == "tello" and s.mode == "SDK" and not s.armed
    assert rig.ext.value.landed_state == LANDED_STATE_ON_GROUND
    assert 0.0 < rig.battery.wait(5).percentage <= 1.0 and math.isnan(rig.battery.value.voltage)
    assert rig.pose.wait(5).header.frame_id == "odom"
    armed = rig.call(registry.ARMING, CommandBool(value=True))
    assert armed.success and "no arming" in armed.message
    battery = rig.call(registry.PARAM_GET, ParamGet(param_id="BATTERY"))
    assert battery.success and 0 < battery.value.real <= 100
    with pytest.raises(ServiceError, match="valid: OFFBOARD"):
        rig.call(registry.SET_MODE, SetMode(custom_mode="ACRO"))
    with pytest.raises(ServiceError, match="altitude"):
        rig.call(registry.TAKEOFF, CommandTOL.takeoff(50.0))  # a Tello: at most 30 m
    with pytest.raises(ServiceError, match="not a Tello parameter"):
        rig.call(registry.PARAM_GET, ParamGet(param_id="MPC_XY_VEL_MAX"))
    landed = rig.call(registry.LAND, CommandTOL.land())
    assert landed.success and "already on the ground" in landed.message
    assert rig.bridge.alive()


def test_takeoff_axes_yaw_stop_position_land(rig):
    rig.take_off(1.2)
    assert rig.state.value.armed  # "armed" = motors running
    # a second take-off is idempotent
    again = rig.call(registry.TAKEOFF, CommandTOL.takeoff(1.2))
    assert again.success and "already flying" in again.message

    forward = rig.fly(velocity(vx=0.4), 1.5)
    assert forward[0] > 0.3 and abs(forward[1]) < 0.15, forward
    left = rig.fly(velocity(vy=0.4), 1.5)
    assert left[1] > 0.3 and abs(left[0]) < 0.15, left  # +vy is left, not right
    up = rig.fly(velocity(vz=0.3), 1.5)
    assert up[2] > 0.2, up
    down = rig.fly(velocity(vz=-0.3), 1.5)
    assert down[2] < -0.2, down

    yaw0 = rig.true_yaw()
    rig.fly(velocity(yaw_rate=0.6), 1.5)
    turned = math.remainder(rig.true_yaw() - yaw0, math.tau)
    assert 0.4 < turned < 1.3, turned  # counter-clockwise, as commanded

    # stop: a zero velocity is a real stop (rc 0 0 0 0), the Tello hovers
    rig.command(velocity(vx=0.5))
    time.sleep(1.0)
    rig.command(velocity())
    time.sleep(1.5)
    assert rig.speed() < 0.1
    rig.command(None)

    # position target on the dead-reckoned estimate: 0.6 m along the estimate's x
    est = rig.pose.wait(5).pose
    start = rig.true_xyz()
    target = PositionTarget(
        coordinate_frame=FRAME_LOCAL_NED,
        type_mask=MASK_POSITION,
        position=Point(x=est.position.x + 0.6, y=est.position.y, z=1.0),
        yaw=yaw_of(rig.pose.value),
    )
    rig.command(target)
    wait_for(
        lambda: (
            abs(rig.pose.value.pose.position.x - target.position.x) < 0.1
            and abs(rig.pose.value.pose.position.z - 1.0) < 0.1
        ),
        15,
        what="position target reached on the estimate",
    )
    rig.command(None)
    assert np.linalg.norm((rig.true_xyz() - start)[:2]) == pytest.approx(0.6, abs=0.2)

    reply = rig.call(registry.LAND, CommandTOL.land())
    assert reply.success, reply.message
    rig.wait_landed()


@pytest.fixture
def short_auto_land_rig(router, spawn) -> Iterator[Rig]:
    """A rig whose Tello lands after AUTO_LAND_S without a command."""
    r = make_rig(router, spawn, "--set", "video=false", auto_land_s=AUTO_LAND_S)
    yield r
    r.close()
    r.user.close()


def test_keepalive_then_failsafe_hold_and_commander_lost_land(short_auto_land_rig):
    rig = short_auto_land_rig
    rig.take_off(1.0)
    # nobody commands for 1.5 auto-land timeouts: the Tello would land; the bridge keeps it alive
    deadline = time.monotonic() + 1.5 * AUTO_LAND_S
    while time.monotonic() < deadline:
        assert rig.true_xyz()[2] > 0.7, "the Tello landed by itself: no keep-alive"
        time.sleep(0.5)
    assert not any(s.failsafe == "land" for s in rig.states)  # no commander yet: no landing

    rig.command(velocity(vx=0.5))
    time.sleep(1.5)
    rig.stream.target = None  # the commander dies: nothing more is sent
    stopped_at = time.monotonic()
    wait_for(lambda: rig.state.value.failsafe == "hold", 3, what="failsafe hold")
    assert time.monotonic() - stopped_at < 1.5
    time.sleep(1.5)
    assert rig.speed() < 0.15  # hovering, not drifting on at the last velocity
    wait_for(lambda: rig.state.value.failsafe == "land", 8, what="commander lost -> land")
    assert time.monotonic() - stopped_at > 4.5
    rig.wait_landed(30)


def test_killed_bridge_the_tello_lands_by_itself(router, spawn):
    rig = make_rig(router, spawn, "--set", "video=false", auto_land_s=AUTO_LAND_S)
    try:
        rig.take_off(1.0)
        rig.bridge.proc.send_signal(signal.SIGKILL)
        rig.bridge.proc.wait(5)
        killed = time.monotonic()
        wait_for(lambda: rig.true_xyz()[2] < 0.05, 35, what="auto-land after the bridge died")
        # the Tello's own timeout, not a crash: the bridge's last command (a keep-alive at
        # most keepalive_s = 3 s before the kill) is AUTO_LAND_S old before the descent starts
        assert time.monotonic() - killed > AUTO_LAND_S - 3.0
    finally:
        rig.close()
        rig.user.close()


class LossyRelay(threading.Thread):
    """Between the bridge and the sim: drops ``loss`` of the command replies.

    Commands go bridge -> relay (``address``:8889) -> sim; the sim answers and streams the state
    to the relay (its commander), which forwards the state to the bridge's 8890.
    """

    def __init__(self, address: str, sim: str, bridge: str, loss: float, seed: int = 5):
        super().__init__(daemon=True)
        self.sim, self.bridge, self.loss = sim, bridge, loss
        self.rng = random.Random(seed)
        self.cmd = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self.cmd.bind((address, 8889))
        self.state = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self.state.bind((address, 8890))
        self.to_sim = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self.to_sim.bind((address, 0))
        for sock in (self.cmd, self.state, self.to_sim):
            sock.settimeout(0.05)
        self.client: tuple[str, int] | None = None
        self.dropped = 0
        self.stop = threading.Event()

    def run(self) -> None:
        while not self.stop.is_set():
            for sock in (self.cmd, self.to_sim, self.state):
                try:
                    data, source = sock.recvfrom(4096)
                except TimeoutError:
                    continue
                except OSError:
                    return
                if sock is self.cmd:
                    self.client = source
                    self.to_sim.sendto(data, (self.sim, 8889))
                elif sock is self.to_sim and self.client is not None:
                    if self.rng.random() < self.loss:
                        self.dropped += 1
                    else:
                        self.cmd.sendto(data, self.client)
                elif sock is self.state:
                    self.state.sendto(data, (self.bridge, 8890))

    def close(self) -> None:
        self.stop.set()
        self.join(2)
        for sock in (self.cmd, self.state, self.to_sim):
            sock.close()


def test_lost_replies_and_malformed_state_strings_survived(router, spawn):
    sim_address, relay_address, bridge_address = (loopback_address() for _ in range(3))
    relay = LossyRelay(relay_address, sim_address, bridge_address, loss=0.3)
    relay.start()
    sim = start_sim(spawn, router, sim_address)
    bridge = start_bridge(spawn, router, relay_address, bridge_address, "--set", "video=false")
    user = client_node(router, name="test")
    rig = Rig(router, sim_address, user, sim, bridge)
    garbage = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    try:
        wait_for(lambda: rig.state.value and rig.state.value.connected, 40, what="connected")
        wait_for(lambda: rig.state.value.guided, 20, what="SDK mode through the lossy link")
        for junk in (b"\xff\xfe\x00", b"pitch:0;roll:x;", b"ok", b"a" * 3000, b"yaw:nan;" * 3):
            garbage.sendto(junk, (bridge_address, 8890))
        answered = 0
        for _ in range(8):  # read commands are retried until a reply gets through
            reply = rig.call(registry.PARAM_GET, ParamGet(param_id="BATTERY"), timeout=20)
            answered += reply.success
        assert answered >= 7, answered
        rig.take_off(1.0)  # its single 'ok' may be lost: the height confirms it
        rig.call(registry.LAND, CommandTOL.land())  # its 'ok' may be lost too: judged from truth
        rig.wait_landed(30)
        assert relay.dropped > 0
        assert bridge.alive() and "malformed state string" in bridge.output()
    finally:
        garbage.close()
        rig.close()
        user.close()
        relay.close()


def test_video_on_demand_decoded_and_published(router, spawn):
    """No stream until a viewer subscribes; live decoded frames while it watches; the sim
    reports the stream off once the viewer has been gone for the idle time."""
    rig = make_rig(router, spawn, "--set", "video=on_demand", "--set", "video_idle_s=1.0")
    try:
        wait_for(lambda: "video: stream off" in rig.bridge.output(), 10, what="streamoff ok")
        assert "video: streaming" not in rig.sim.output()  # connected, nobody watching
        with client_node(router, name="viewer") as viewer:
            frames = viewer.latest(registry.IMAGE_RAW, camera="cam_frontal")
            first = frames.wait(30)
            assert (first.width, first.height, first.encoding) == (960, 720, "bgr8")
            assert first.header.frame_id == "cam_frontal"
            seqs, ages = [], []
            deadline = time.monotonic() + 3.0
            while time.monotonic() < deadline:
                msg = frames.wait(5, newer_than=frames.count)
                seqs.append(msg.header.seq)
                ages.append(time.time() - msg.header.stamp)
            assert len(set(seqs)) > 10  # a live stream, not one frame
            assert float(np.median(ages)) < 0.5
            image = np.frombuffer(first.data, np.uint8).reshape(720, 960, 3)
            assert image.std() > 5.0  # a rendered scene, not a blank frame
            jpeg = viewer.latest(registry.IMAGE_COMPRESSED, camera="cam_frontal")
            assert jpeg.wait(10).format == "jpeg"  # compressed on request
            assert rig.sim.output().count("video: streaming") == 1
            leaving = time.monotonic()  # closing the viewer's session undeclares its subscribers
        wait_for(lambda: "video: stream off" in rig.sim.output(), 20, what="the stream off")
        assert time.monotonic() - leaving >= 1.0  # not before the idle time
    finally:
        rig.close()
        rig.user.close()


def test_reconnects_after_the_tello_restarts(router, spawn):
    rig = make_rig(router, spawn, "--set", "video=false")
    try:
        rig.sim.stop()
        wait_for(lambda: not rig.state.value.connected, 10, what="link lost reported")
        assert rig.bridge.alive()
        rig.sim = start_sim(spawn, router, rig.address)  # a power-cycled Tello, same address
        wait_for(
            lambda: rig.state.value.connected and rig.state.value.guided,
            40,
            what="reconnected and back in SDK mode",
        )
        rig.take_off(1.0)
        reply = rig.call(registry.LAND, CommandTOL.land())
        assert reply.success, reply.message
        rig.wait_landed()
    finally:
        rig.close()
        rig.user.close()
