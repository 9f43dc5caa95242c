"""bridge_tello against the simulated Tello over real UDP, judged from the sim's ground truth.

Every test runs the real processes: a Zenoh router (fixture), ``python -m dronewrapper_sim
--aircraft tello`` on its own loopback address, and ``python -m dronewrapper_bridge_tello``
bound to the same address, and drives the bridge at key level the way the SDK does: what only
real processes show (the SDK's text over real UDP sockets, a killed bridge, a restarted Tello,
the video stream). The bridge's flight logic (axes, yaw, stop, position targets, keep-alive,
the failsafes' timings, lost replies, malformed state strings) is held in virtual time by
tests/service/test_tello_flight_virtual.py. Height is judged in the sim's true ENU frame
(``{ns}/sim/ground_truth``). Waits are bounded and generous (2 shared cores).
"""

from __future__ import annotations

import math
import random
import signal
import time
from collections.abc import Iterator
from dataclasses import dataclass

import numpy as np
import pytest
from bridge_user import BridgeUser

from dronewrapper.msgs import registry
from dronewrapper.msgs.mavros import (
    LANDED_STATE_IN_AIR,
    LANDED_STATE_ON_GROUND,
    CommandBool,
    CommandTOL,
    ParamGet,
    SetMode,
)
from dronewrapper.runtime import Node, ServiceError
from support import client_node, python_module, wait_for

pytestmark = pytest.mark.integration


def loopback_address() -> str:
    """A loopback address of our own, so 8889/8890/11111 never clash with another test."""
    return f"127.{random.randint(10, 250)}.{random.randint(0, 255)}.{random.randint(2, 250)}"


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

    def take_off(self, height: float = 1.2) -> None:
        reply = self.call(registry.TAKEOFF, CommandTOL.takeoff(height))
        assert reply.success, reply.message
        assert self.true_xyz()[2] == pytest.approx(height, abs=0.15), reply.message
        wait_for(
            lambda: self.ext.value and self.ext.value.landed_state == LANDED_STATE_IN_AIR,
            5,
            what="landed_state IN_AIR",
        )

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


def make_rig(router, spawn, *bridge_args: str, auto_land_s: float | None = None) -> Rig:
    address = loopback_address()
    sim = start_sim(spawn, router, address, auto_land_s)
    bridge = start_bridge(spawn, router, address, address, *bridge_args)
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
