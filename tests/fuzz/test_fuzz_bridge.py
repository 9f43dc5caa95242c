"""Fuzz the bridge in-process: every service and its subscribed key, and its MAVLink input.

The bridge runs on a real router and faces an AutopilotPeer over real UDP loopback. Each example
is a payload built from a request that WOULD act (arm, take off, land, set a mode, write a
parameter) and then broken one way (fuzz_inputs.py). Asserted for every example: an error reply
(never an OK one) that names the problem, nothing the autopilot could act on left the bridge,
and the bridge keeps running. The same rig then proves the assertion can fail: the unbroken
request does reach the autopilot.
"""

from __future__ import annotations

import math
import random
import time

import pytest
from bridge_rig import bridge_rig
from fuzz_calls import assert_refused, call_raw
from fuzz_inputs import REQUESTS, SETPOINT_BASE, Bad, bad_setpoint
from hypothesis import HealthCheck, given, settings
from pymavlink.dialects.v20 import common as mavlink

from dronewrapper.msgs import codec, registry
from support import wait_for, zenoh_router

pytestmark = pytest.mark.fuzz

FUZZ = settings(
    max_examples=40,
    deadline=None,  # a loaded machine: judge by outcomes, never by time
    derandomize=True,  # the same examples on every run (CI)
    database=None,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large],
)


@pytest.fixture(scope="module")
def rig():
    with zenoh_router() as router, bridge_rig(router) as rig:
        yield rig


def assert_alive(rig) -> None:
    assert rig.bridge.core.connected, "the bridge lost its autopilot"
    assert not rig.bridge.node.stop_event.is_set()
    assert rig.bridge.node.callback_errors.get("mavlink", 0) == 0


@pytest.mark.parametrize("name", sorted(REQUESTS))
def test_every_service_refuses_bad_requests_and_actuates_nothing(rig, name):
    shape = REQUESTS[name]
    since = time.monotonic()

    assert_refused(rig.user, shape, FUZZ)
    time.sleep(0.2)  # anything sent would have left by now (sends are synchronous)
    assert rig.peer.actuating(since) == []
    assert_alive(rig)


def test_the_assertion_can_fail_an_unbroken_request_does_reach_the_autopilot(rig):
    since = time.monotonic()
    arm = codec.encode(REQUESTS["arming"].service.request(value=True))
    reply = call_raw(rig.user, registry.ARMING, arm)
    assert reply.ok is not None  # the peer refuses (UNSUPPORTED), but the command went out
    sent = wait_for(lambda: rig.peer.actuating(since), 10, what="the arming command on the wire")
    assert sent[0].get_type() == "COMMAND_LONG" and sent[0].command == 400


def test_bad_setpoints_are_each_refused_and_never_forwarded(rig):
    bridge, node = rig.bridge, rig.bridge.node
    key = registry.SETPOINT_RAW_LOCAL.key("drone")
    since = time.monotonic()

    def refused_count() -> int:
        return bridge.core.rejected_setpoints + sum(node.decode_errors.values())

    @FUZZ
    @given(bad=bad_setpoint())
    def refused(bad: Bad) -> None:
        before = refused_count()
        rig.user.session.put(key, bad.payload)
        wait_for(lambda: refused_count() > before, 10, interval=0.005, what=f"{bad} refused")

    refused()
    time.sleep(0.2)
    assert not [m for m in rig.peer.actuating(since) if "POSITION_TARGET" in m.get_type()]
    assert bridge.core.failsafe.fresh_target(time.monotonic()) is None  # nothing was taken as valid
    assert_alive(rig)
    assert codec.decode(registry.SETPOINT_RAW_LOCAL.type, codec.encode(SETPOINT_BASE)) is not None


def _mavlink_frames(peer, rng: random.Random) -> list[bytes]:
    """Garbage, bit-flipped, truncated and non-finite MAVLink traffic."""
    nan, inf, t = math.nan, math.inf, peer.boot_ms()
    big, small = 2**31 - 1, -(2**31)
    valid = [
        mavlink.MAVLink_local_position_ned_message(peer.boot_ms(), nan, inf, -inf, nan, 0, 0),
        mavlink.MAVLink_attitude_message(peer.boot_ms(), nan, inf, nan, inf, nan, 0),
        mavlink.MAVLink_attitude_quaternion_message(t, nan, 0, 0, 0, inf, 0, 0, [0] * 4),
        mavlink.MAVLink_global_position_int_message(t, big, small, 0, 0, 0, 0, 0, 0),
        mavlink.MAVLink_extended_sys_state_message(255, 255),
        mavlink.MAVLink_sys_status_message(0, 0, 0, 0, 65535, -1, -1, 0, 0, 0, 0, 0, 0),
        mavlink.MAVLink_statustext_message(255, b"\xff" * 50),
        mavlink.MAVLink_command_ack_message(400, 255, 0, 0, 0, 0),
        mavlink.MAVLink_param_value_message(b"MPC_XY_VEL_MAX", nan, 255, 65535, 65535),
        mavlink.MAVLink_home_position_message(0, 0, 0, nan, inf, nan, [nan] * 4, nan, nan, nan),
        mavlink.MAVLink_battery_status_message(0, 0, 0, 32767, [65535] * 10, -1, -1, -1, -128),
    ]  # fmt: skip
    frames = []
    for msg in valid:
        data = peer.pack(msg)
        frames.append(data)
        flipped = bytearray(data)
        flipped[rng.randrange(len(flipped))] ^= 1 << rng.randrange(8)
        frames.append(bytes(flipped))
        frames.append(data[: rng.randrange(1, len(data))])
    frames += [rng.randbytes(rng.randrange(1, 300)) for _ in range(60)]
    frames.append(b"\xfd" + b"\xff" * 279)  # a MAVLink 2 start with an absurd header
    return frames


def test_bad_mavlink_traffic_never_breaks_the_bridge(rig):
    rng = random.Random(12)
    since = time.monotonic()
    before = rig.bridge.core.messages_received
    for data in _mavlink_frames(rig.peer, rng):
        rig.peer.send_raw(data)
    wait_for(lambda: rig.bridge.core.messages_received > before + 20, 10)
    time.sleep(0.5)
    assert_alive(rig)
    for pose in rig.poses.values(since):
        p = pose.pose.position
        assert math.isfinite(p.x) and math.isfinite(p.y) and math.isfinite(p.z), pose
    assert rig.peer.actuating(since) == []
