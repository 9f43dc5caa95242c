"""bridge_tello's Bridge in-process against a scripted Tello over real UDP, on the fake bus
(the command lease, carried as a Zenoh attachment, on a real router).

The scripted Tello (tests/tello_peer.py) answers from a script and records every datagram, so
what the bridge puts on the wire (rc text, signs, rate, the stop) is checked exactly.
"""

from __future__ import annotations

import random
import time
from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any

import pytest
from tello_peer import ScriptedTello

from dronewrapper.msgs import registry
from dronewrapper.msgs.geometry import Vector3
from dronewrapper.msgs.lease import LeaseRequest
from dronewrapper.msgs.mavros import (
    FRAME_BODY_NED,
    MASK_VELOCITY,
    CommandTOL,
    ParamGet,
    ParamSet,
    ParamValue,
    PositionTarget,
    SetMode,
)
from dronewrapper.runtime import ServiceError, call_service
from dronewrapper.runtime.caller import commander_attachment
from dronewrapper.runtime.config import load_config
from dronewrapper.runtime.fake import FakeBus, FakeNode
from dronewrapper_bridge_tello.node import Bridge, Config
from support import client_node, wait_for


@contextmanager
def running_bridge(
    extra: list[str], router: str = ""
) -> Iterator[tuple[ScriptedTello, Bridge, Any]]:
    """A scripted Tello on a random loopback address and a started Bridge talking to it, with a
    user node: on the fake bus, or on a real Zenoh router when ``router`` is given."""
    address = f"127.{random.randint(10, 250)}.{random.randint(0, 255)}.{random.randint(2, 250)}"
    tello = ScriptedTello(address)
    tello.start()
    config = load_config(
        Config,
        None,
        [f"tello_address={address}", f"local_address={address}", "video=false", *extra],
    )
    if router:
        node = client_node(router, name="bridge_tello", mode="client")
        user = client_node(router, name="test", mode="client")
    else:
        bus = FakeBus()
        node, user = FakeNode("bridge_tello", bus), FakeNode("test", bus)
    bridge = Bridge(node, config)
    threads = bridge.start()
    try:
        wait_for(lambda: bridge.connected and bridge.sdk_mode, 10, what="bridge connected")
        yield tello, bridge, user
    finally:
        node.stop()
        for thread in threads:
            thread.join(2)
        bridge.link.close()
        user.close()
        node.close()
        tello.stop.set()
        tello.join(2)
        tello.sock.close()


@pytest.fixture
def tello_and_bridge(request) -> Iterator[tuple[ScriptedTello, Bridge, Any]]:
    """The bridge on the fake bus (the Tello link stays real UDP)."""
    with running_bridge(getattr(request, "param", [])) as running:
        yield running


def test_refusals_carry_the_tellos_text(tello_and_bridge):
    tello, bridge, user = tello_and_bridge
    tello.script["takeoff"] = "error No valid imu"
    reply = user.call(registry.TAKEOFF, CommandTOL.takeoff(), timeout=30)
    assert not reply.success and reply.result == 2
    assert "error No valid imu" in reply.message
    assert not bridge.telemetry.landed.flying
    tello.script["speed 50"] = "out of range"
    reply = user.call(registry.PARAM_SET, ParamSet(param_id="SPEED", value=ParamValue.of(50)))
    assert not reply.success and "out of range" in reply.message
    with pytest.raises(ServiceError, match=r"\[10, 100\]"):
        user.call(registry.PARAM_SET, ParamSet(param_id="SPEED", value=ParamValue.of(500)))
    reply = user.call(registry.PARAM_SET, ParamSet(param_id="BATTERY", value=ParamValue.of(5)))
    assert not reply.success and "read-only" in reply.message


@pytest.mark.parametrize("tello_and_bridge", [["command_timeout=0.3"]], indirect=True)
def test_silence_is_retried_then_reported(tello_and_bridge):
    tello, _, user = tello_and_bridge
    tello.script["speed?"] = None
    reply = user.call(registry.PARAM_GET, ParamGet(param_id="SPEED"), timeout=10)
    assert not reply.success and "no reply" in reply.message
    asked = [text for _, text in tello.received if text == "speed?"]
    assert len(asked) == 3  # command_attempts
    reply = user.call(registry.PARAM_GET, ParamGet(param_id="BATTERY"))
    assert reply.success and reply.value.real == 80.0  # not confused by the silence before


def test_rc_on_the_wire_signs_rate_and_a_real_stop(tello_and_bridge):
    tello, bridge, user = tello_and_bridge
    assert user.call(registry.TAKEOFF, CommandTOL.takeoff(), timeout=30).success
    pub = user.publisher(registry.SETPOINT_RAW_LOCAL)
    # forward 0.3, left 0.2, up 0.1 m/s, CCW 0.4 rad/s -> a -20, b 30, c 10, d -23
    target = PositionTarget(
        coordinate_frame=FRAME_BODY_NED,
        type_mask=MASK_VELOCITY,
        velocity=Vector3(x=0.3, y=0.2, z=0.1),
        yaw_rate=0.4,
    )
    start = time.monotonic()
    while time.monotonic() - start < 1.3:
        pub.put(target)
        time.sleep(0.05)
    stopped = time.monotonic()
    # the last setpoint stays fresh for setpoint_timeout (0.5 s), then: a real stop, not silence
    wait_for(lambda: (0, 0, 0, 0) in {s for _, s in tello.rcs(stopped)}, 5, what="a stop")
    stops = [t for t, s in tello.rcs(stopped) if s == (0, 0, 0, 0)]
    assert stops[0] - stopped < 0.5 + 0.2
    wait_for(lambda: len(tello.rcs(stops[0])) >= 5, 5, what="rc after the stop")
    commanded = [s for t, s in tello.rcs(start + 0.3) if t < stopped]
    assert commanded and set(commanded) == {(-20, 30, 10, -23)}
    assert len(commanded) >= 0.85 * 20 * 1.0  # >= 20 Hz while commanded (bounded jitter)
    assert all(s == (0, 0, 0, 0) for _, s in tello.rcs(stops[0]))
    assert bridge.failsafe.state == "hold"
    # clamped: 5 m/s is refused as a setpoint (beyond limits), 2.5 m/s is clamped to 100
    fast = PositionTarget(
        coordinate_frame=FRAME_BODY_NED, type_mask=MASK_VELOCITY, velocity=Vector3(x=2.5)
    )
    t0 = time.monotonic()
    for _ in range(10):
        pub.put(fast)
        time.sleep(0.05)
    assert (0, 100, 0, 0) in {s for _, s in tello.rcs(t0)}


def test_modes_mapped_to_tello_commands(tello_and_bridge):
    tello, _, user = tello_and_bridge
    with pytest.raises(ServiceError, match="valid: OFFBOARD"):
        user.call(registry.SET_MODE, SetMode(custom_mode="STABILIZED"))
    assert user.call(registry.SET_MODE, SetMode(custom_mode="AUTO.LOITER")).mode_sent
    assert user.call(registry.SET_MODE, SetMode(custom_mode="OFFBOARD")).mode_sent
    sent = [text for _, text in tello.received if not text.startswith("rc ")]
    assert sent[-2:] == ["stop", "command"]


def test_a_second_bridge_on_the_same_address_fails_loudly(tello_and_bridge):
    _, bridge, user = tello_and_bridge
    with pytest.raises(OSError):
        Bridge(user, bridge.config)
    assert bridge.connected


def test_command_lease_one_commander_at_a_time(router):
    """On a real router: the commander travels as a Zenoh attachment (the wiring)."""
    with running_bridge(["command_lease=true"], router) as (tello, bridge, user):

        def call(service, request, who: str):
            return call_service(
                user.session, service, request, ns="drone", timeout=30,
                attachment=commander_attachment(who),
            )  # fmt: skip

        assert call(registry.TAKEOFF, CommandTOL.takeoff(), "alice").success
        with pytest.raises(ServiceError, match="holds the command lease"):
            call(registry.LAND, CommandTOL.land(), "bob")
        assert tello.flying  # bob's land never reached the Tello
        taken = call(registry.COMMAND_LEASE, LeaseRequest(action="take_over"), "bob")
        assert taken.granted and taken.holder == "bob" and taken.previous == "alice"
        wait_for(lambda: bridge.state_message().commander == "bob", 5, what="State.commander")
        assert call(registry.LAND, CommandTOL.land(), "bob").success
