"""bridge_tello's flight logic against the simulated Tello in virtual time, judged from truth.

The real ``Bridge`` (its reply, state and control threads) runs on a fake bus, its link the
simulator's Tello in process on the node's clock (tests/clocked_tello.py: the SDK's text both
ways). A test drives it at key level as an app does, its commander's 20 Hz stream a worker
of the same clock (tests/clocked_setpoints.py), and judges directions in the sim's true ENU
frame. Every timing checked here is the bus's virtual time, exact however loaded the machine.
The real UDP path (sockets, process kill and restart, video) stays in
tests/integration/test_tello_bridge_sim.py.
"""

from __future__ import annotations

import logging
import math
import random
from collections.abc import Callable, Iterator
from dataclasses import replace

import numpy as np
import pytest
from clocked_tello import ClockedTello
from targets import velocity
from virtual_bridge import VirtualBridge

from dronewrapper.msgs import registry
from dronewrapper.msgs.geometry import Point
from dronewrapper.msgs.mavros import (
    FRAME_LOCAL_NED,
    LANDED_STATE_IN_AIR,
    LANDED_STATE_ON_GROUND,
    MASK_POSITION,
    CommandTOL,
    ParamGet,
    PositionTarget,
)
from dronewrapper.runtime.fake import FakeNode
from dronewrapper_bridge_tello import node as tello_node
from dronewrapper_bridge_tello.config import Config
from dronewrapper_sim.tello.flight import TelloFlight
from dronewrapper_sim.tello.params import TELLO

AUTO_LAND_S = 8.0
"""The simulated Tello's auto-land timeout where a test waits for it (the real drone's 15 s is
the default): a keep-alive every ``keepalive_s`` (3 s) must still beat it."""


class LossyTello(ClockedTello):
    """The clocked Tello whose command replies are lost with probability ``loss`` (seeded)."""

    def __init__(self, *args, loss: float, seed: int = 5, **kwargs) -> None:
        super().__init__(*args, **kwargs)
        self.loss, self.rng, self.dropped = loss, random.Random(seed), 0

    def _reply(self, replies: list) -> None:
        kept = []
        for reply in replies:
            if self.rng.random() < self.loss:
                self.dropped += 1
            else:
                kept.append(reply)
        super()._reply(kept)


class Rig(VirtualBridge):
    """A started Tello bridge on a fake bus facing ``tello`` (tests/virtual_bridge.py)."""

    CALL_TIMEOUT_S = 40.0

    def __init__(self, tello: Callable[[FakeNode], ClockedTello] | None = None) -> None:
        super().__init__()
        make = tello or (lambda node: ClockedTello(node.clock, node.stop_event))
        self.tello = make(self.node)
        self.start(tello_node.Bridge(self.node, Config(video=False), link=self.tello))

    @property
    def truth(self):
        return self.tello.protocol.flight.state

    def true_xyz(self) -> np.ndarray:
        with self.tello.lock:
            self.tello.catch_up()
            return np.array([self.truth.x, self.truth.y, self.truth.z])

    def true_yaw(self) -> float:
        with self.tello.lock:
            self.tello.catch_up()
            return self.truth.yaw

    def connect(self) -> None:
        self.wait_for(
            lambda: self.state.value and self.state.value.connected and self.state.value.guided,
            40,
            "bridge connected and in SDK mode",
        )

    def take_off(self, height: float = 1.2) -> None:
        reply = self.call(registry.TAKEOFF, CommandTOL.takeoff(height))
        assert reply.success, reply.message
        assert self.true_xyz()[2] == pytest.approx(height, abs=0.15), reply.message
        self.wait_for(
            lambda: self.ext.value and self.ext.value.landed_state == LANDED_STATE_IN_AIR,
            5,
            "landed_state IN_AIR",
        )

    def fly(self, target: PositionTarget, seconds: float) -> np.ndarray:
        """Command ``target`` for ``seconds`` from a 1 s standstill; the true displacement in
        the body axes (forward, left, up) of the heading at the start, m."""
        self.command(velocity())
        self.run(1.0)
        start, yaw = self.true_xyz(), self.true_yaw()
        self.command(target)
        self.run(seconds)
        self.command(None)
        moved = self.true_xyz() - start
        c, s = math.cos(yaw), math.sin(yaw)
        return np.array([c * moved[0] + s * moved[1], -s * moved[0] + c * moved[1], moved[2]])

    def speed(self, window: float = 0.3) -> float:
        """True horizontal+vertical speed over ``window`` s (m/s)."""
        a = self.true_xyz()
        self.run(window)
        return float(np.linalg.norm(self.true_xyz() - a) / window)

    def wait_landed(self, timeout: float = 40.0) -> None:
        self.wait_for(lambda: self.true_xyz()[2] < 0.05, timeout, "on the ground (truth)")
        self.wait_for(
            lambda: self.ext.value and self.ext.value.landed_state == LANDED_STATE_ON_GROUND,
            10,
            "landed_state ON_GROUND",
        )
        self.wait_for(lambda: self.state.value and not self.state.value.armed, 5, "disarmed")


@pytest.fixture
def rig() -> Iterator[Rig]:
    made = Rig()
    made.connect()
    yield made
    made.close()


def yaw_of(pose) -> float:
    q = pose.pose.orientation
    return math.atan2(2.0 * (q.w * q.z + q.x * q.y), 1.0 - 2.0 * (q.y * q.y + q.z * q.z))


def test_takeoff_axes_yaw_stop_position_land(rig: Rig):
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
    rig.run(1.0)
    rig.command(velocity())
    rig.run(1.5)
    assert rig.speed() < 0.1
    rig.command(None)

    # position target on the dead-reckoned estimate: 0.6 m along the estimate's x
    est = rig.pose.value.pose
    start = rig.true_xyz()
    target = PositionTarget(
        coordinate_frame=FRAME_LOCAL_NED,
        type_mask=MASK_POSITION,
        position=Point(x=est.position.x + 0.6, y=est.position.y, z=1.0),
        yaw=yaw_of(rig.pose.value),
    )
    rig.command(target)
    rig.wait_for(
        lambda: (
            abs(rig.pose.value.pose.position.x - target.position.x) < 0.1
            and abs(rig.pose.value.pose.position.z - 1.0) < 0.1
        ),
        15,
        "position target reached on the estimate",
    )
    rig.command(None)
    assert np.linalg.norm((rig.true_xyz() - start)[:2]) == pytest.approx(0.6, abs=0.2)

    reply = rig.call(registry.LAND, CommandTOL.land())
    assert reply.success, reply.message
    rig.wait_landed()


def test_keepalive_then_failsafe_hold_and_commander_lost_land():
    flight = TelloFlight(envelope=replace(TELLO, auto_land_s=AUTO_LAND_S))
    rig = Rig(lambda node: ClockedTello(node.clock, node.stop_event, flight))
    try:
        rig.connect()
        rig.take_off(1.0)
        # nobody commands for 1.5 auto-land timeouts: the Tello would land; the bridge keeps
        # it alive
        for _ in range(int(1.5 * AUTO_LAND_S / 0.5)):
            assert rig.true_xyz()[2] > 0.7, "the Tello landed by itself: no keep-alive"
            rig.run(0.5)
        assert not any(s.failsafe == "land" for s in rig.states)  # no commander yet: no landing

        rig.command(velocity(vx=0.5))
        rig.run(1.5)
        rig.command(None)  # the commander dies: nothing more is sent
        last = rig.stream.sent[-1]  # the clock's time of the last setpoint
        rig.wait_for(lambda: rig.state.value.failsafe == "hold", 3, "failsafe hold")
        # setpoint_timeout 0.5 s after the last setpoint, to the control tick (1/20 s) and the
        # State on change: the real-process test allowed anything under 1.5 s
        assert 0.5 <= rig.clock.time() - last < 0.5 + 3 / 20
        rig.run(1.5)
        assert rig.speed() < 0.15  # hovering, not drifting on at the last velocity
        rig.wait_for(lambda: rig.state.value.failsafe == "land", 8, "commander lost -> land")
        # commander_lost_timeout 5 s, the same way (the real-process test: over 4.5 s)
        assert 5.0 <= rig.clock.time() - last < 5.0 + 3 / 20
        rig.wait_landed(30)
    finally:
        rig.close()


def test_lost_replies_and_malformed_state_strings_survived(caplog):
    caplog.set_level(logging.WARNING)
    rig = Rig(lambda node: LossyTello(node.clock, node.stop_event, loss=0.3))
    try:
        rig.wait_for(lambda: rig.state.value and rig.state.value.connected, 40, "connected")
        rig.wait_for(lambda: rig.state.value.guided, 20, "SDK mode through the lossy link")
        with rig.tello.lock:  # datagrams no Tello sends, on the state port
            rig.tello.state.inbox.extend(
                [b"\xff\xfe\x00", b"pitch:0;roll:x;", b"ok", b"a" * 3000, b"yaw:nan;" * 3]
            )
        answered = 0
        for _ in range(8):  # read commands are retried until a reply gets through
            asked = rig.clock.monotonic()
            reply = rig.call(registry.PARAM_GET, ParamGet(param_id="BATTERY"))
            assert rig.clock.monotonic() - asked < 20.0  # the integration test's call timeout
            answered += reply.success
        assert answered >= 7, answered
        rig.take_off(1.0)  # its single 'ok' may be lost: the height confirms it
        rig.call(registry.LAND, CommandTOL.land())  # its 'ok' may be lost too: judged from truth
        rig.wait_landed(30)
        assert rig.tello.dropped > 0
        assert rig.alive() and "malformed state string" in caplog.text
        assert rig.bridge.core.malformed_states >= 4  # the junk, not a valid string, refused
    finally:
        rig.close()
