"""The SDK's Zenoh wiring, on a real router with the small fake bridge (tests/fake_bridge.py).

What only a real session shows: the constructor waits for the bridge and every stream, and
says which is missing (no router, no bridge, no autopilot, wrong namespace); the setpoint
stream keeps its rate on the wire; namespaces keep two drones apart; a session can be shared;
a script that never closes still exits; cameras are pulled only when read. The SDK's logic
(take-off and landing, services, setpoints, getters, errors) is tested on the fake bus in
tests/service/test_sdk_drone.py and test_sdk_aio.py.
"""

from __future__ import annotations

import itertools
import subprocess
import sys
import time
from collections.abc import Iterator

import pytest

from dronewrapper import DroneWrapper, NoData, NotConnected, list_drones
from dronewrapper.msgs import PositionTarget, registry
from dronewrapper.msgs.mavros import LANDED_STATE_ON_GROUND, MASK_POSITION
from fake_bridge import FakeBridge
from support import client_node, free_endpoint, wait_for

pytestmark = pytest.mark.integration


@pytest.fixture
def bridge(router) -> Iterator[FakeBridge]:
    fake = FakeBridge(router)
    yield fake
    fake.close()


@pytest.fixture
def drone(router, bridge) -> Iterator[DroneWrapper]:
    with DroneWrapper("drone", router, timeout=10) as wrapper:
        yield wrapper


def test_set_cmd_vel_is_streamed_at_20_hz_or_more_until_changed(drone, bridge):
    t0 = time.monotonic()
    drone.set_cmd_vel(az=1)
    wait_for(lambda: len(bridge.setpoints_since(t0)) >= 31, 10, what="31 setpoints arrived")
    with bridge.lock:
        times = [t for t, _ in bridge.setpoints if t >= t0]
    # >= 20 Hz (30 Hz nominal), judged by the median gap between arrivals: a busy machine may
    # stall the process now and then (a lost tick or two), a slow stream shifts every gap
    gaps = sorted(b - a for a, b in itertools.pairwise(times))
    median = gaps[len(gaps) // 2]
    assert median <= 1.0 / 20.0, f"median gap {median * 1000:.0f} ms"
    got = bridge.setpoints_since(t0)
    assert all(m.type_mask == 1991 and m.coordinate_frame == 8 and m.yaw_rate == 1 for m in got)
    drone.set_cmd_mix(vx=0.5, z=2.0, az=0.1, stamp=1.7e9)

    def latest_mixed() -> PositionTarget | None:
        last = bridge.setpoints_since(t0)[-1]
        return last if last.type_mask != 1991 else None

    latest = wait_for(latest_mixed, 10, what="mixed setpoint")
    assert latest.type_mask == 1987 and latest.position.z == 2.0 and latest.velocity.x == 0.5
    assert latest.header.stamp == 1.7e9
    drone.stop_commanding()
    sent = drone.setpoints_sent
    bridge.wait_quiet()
    assert max(m.header.seq for m in bridge.setpoints_since(t0)) < sent  # none after the stop


def test_two_drones_by_namespace_do_not_cross_talk(router):
    one, two = FakeBridge(router, "drone1"), FakeBridge(router, "drone2")
    try:
        with (
            DroneWrapper("drone1", router) as d1,
            DroneWrapper("drone2", router) as d2,
        ):
            assert list_drones(router) == ["drone1", "drone2"]
            d1.set_cmd_vel(vx=1.0)
            d2.set_cmd_pos(z=2.0)
            wait_for(
                lambda: len(one.setpoints) >= 5 and len(two.setpoints) >= 5, 10, what="setpoints"
            )
            assert all(m.type_mask == 1991 for _, m in one.setpoints)
            assert all(m.type_mask == MASK_POSITION for _, m in two.setpoints)
    finally:
        one.close()
        two.close()


def test_no_router_is_a_clear_error():
    endpoint = free_endpoint()
    t0 = time.monotonic()
    with pytest.raises(NotConnected, match=f"cannot reach the Zenoh router at {endpoint}"):
        DroneWrapper("drone", endpoint, timeout=1.0)
    assert time.monotonic() - t0 < 10
    with pytest.raises(NotConnected, match="cannot reach"):
        list_drones(endpoint, timeout=0.5)
    with pytest.raises(NotConnected, match=f"cannot reach the Zenoh router at {endpoint}"):
        DroneWrapper("drone", endpoint, timeout=1.0, mode="peer")  # a peer opens regardless


def test_no_bridge_is_a_clear_error(router):
    with pytest.raises(NotConnected, match=r"no bridge for drone 'drone'.*nothing published"):
        DroneWrapper("drone", router, timeout=1.0)


def test_bridge_without_autopilot_is_a_clear_error(router):
    fake = FakeBridge(router, connected=False)
    try:
        # long enough for the fake's first State to arrive on a busy machine
        with pytest.raises(NotConnected, match="bridge of drone 'drone' is up but its autopilot"):
            DroneWrapper("drone", router, timeout=3.0)
    finally:
        fake.close()


def test_wrong_namespace_hints_at_the_drones_online(router, bridge):
    with pytest.raises(NotConnected, match="drones online: drone"):
        DroneWrapper("drone7", router, timeout=1.0)


def test_embedding_on_an_existing_node(router, bridge):
    node = client_node(router, name="embedder")
    try:
        drone = DroneWrapper(name="drone", node=node, cameras=(), wait=False)
        drone.wait_for_connection(10)
        drone.set_cmd_vel(vz=0.1)
        wait_for(lambda: bridge.setpoints, 10, what="setpoint from the embedded SDK")
        drone.close()
        assert not node.session.is_closed()  # the owner's node stays open
    finally:
        node.close()


def test_a_script_that_never_closes_exits_and_stops_commanding(router, bridge):
    """The paper's listing never calls close(): the interpreter must still exit promptly."""
    script = (
        "import sys\n"
        "from dronewrapper import DroneWrapper\n"
        "drone = DroneWrapper('drone', sys.argv[1], mode='peer')\n"
        "drone.set_cmd_vel(az=1)\n"
    )
    t0 = time.monotonic()
    proc = subprocess.run(
        [sys.executable, "-c", script, router], capture_output=True, text=True, timeout=60
    )
    assert proc.returncode == 0, proc.stderr
    assert time.monotonic() - t0 < 30
    wait_for(lambda: bridge.setpoints, 10, what="the script's setpoint")
    bridge.wait_quiet()  # nobody streams after the app is gone


def test_constructor_waits_for_every_stream_and_names_a_missing_one(router):
    fake = FakeBridge(router)
    fake.silent.add(registry.BATTERY.key("drone"))
    try:
        with pytest.raises(NotConnected, match=r"nothing arrived on: battery state \(drone/mavros"):
            DroneWrapper("drone", router, timeout=3)
        fake.silent.clear()
        with DroneWrapper("drone", router, timeout=10) as drone:
            # right after the constructor, every getter has a value (no NoData race)
            assert drone.get_battery() == pytest.approx(0.8)
            assert drone.get_landed_state() == LANDED_STATE_ON_GROUND
            assert drone.get_velocity_local().shape == (3,)
    finally:
        fake.close()


def test_cameras_are_subscribed_only_when_read(drone, bridge):
    """A program that never reads a frame never pulls one across the network."""
    publisher = bridge.pub_image._pub
    time.sleep(0.5)
    assert not publisher.matching_status.matching
    assert not drone.compressed_images  # the router is on this machine: raw frames
    with pytest.raises(NoData, match="no image received yet"):
        drone.get_frontal_image()
    wait_for(lambda: publisher.matching_status.matching, 10, what="a camera subscriber")
