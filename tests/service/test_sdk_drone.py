"""DroneWrapper against the small fake bridge (tests/fake_bridge.py), on a real Zenoh router.

The fake answers the bridge's services and publishes its telemetry like the real one; a
"physics" thread moves the altitude toward a position setpoint when armed in OFFBOARD. It lets
these tests check the SDK's side of the contract precisely (order of calls, keys, masks,
rates, error messages) in a fraction of a second per test.
"""

from __future__ import annotations

import itertools
import logging
import math
import subprocess
import sys
import time
from collections.abc import Iterator

import numpy as np
import pytest

from dronewrapper import (
    CommandRefused,
    DroneWrapper,
    InvalidArgument,
    NoData,
    NotConnected,
    Timeout,
    list_drones,
)
from dronewrapper.msgs import (
    PositionTarget,
    registry,
)
from dronewrapper.msgs.mavros import (
    LANDED_STATE_ON_GROUND,
    MASK_POSITION,
    MAV_RESULT_DENIED,
)
from fake_bridge import FakeBridge
from support import client_node, free_endpoint, wait_for


@pytest.fixture
def bridge(router) -> Iterator[FakeBridge]:
    fake = FakeBridge(router)
    yield fake
    fake.close()


@pytest.fixture
def drone(router, bridge) -> Iterator[DroneWrapper]:
    with DroneWrapper("drone", router, timeout=10) as wrapper:
        yield wrapper


def test_getters_return_latest_values_at_once(drone, bridge):
    wait_for(lambda: drone.get_position()[0] == 1.0, 10, what="pose")
    assert isinstance(drone.get_position(), np.ndarray)
    assert drone.get_position().shape == (3,)
    assert drone.wait_for(drone.get_position, 1, "position").shape == (3,)  # arrays count
    assert drone.wait_for_altitude(0.0, timeout=1)[0] == 1.0
    with pytest.raises(Timeout, match=r"altitude 3\.00 m .*now z=0\.00 m"):
        drone.wait_for_altitude(3.0, timeout=0.2)
    assert drone.get_orientation().tolist() == [0.0, 0.0, 0.0]
    assert drone.get_yaw_rate() == 0.25
    assert drone.get_velocity().tolist() == [0.0, 0.0, 0.0]
    assert drone.get_landed_state() == LANDED_STATE_ON_GROUND
    state = drone.get_state()
    assert state.connected and state.autopilot == "px4"
    assert drone.is_connected()
    assert drone.get_battery() == pytest.approx(0.8)  # the constructor waited for it
    with pytest.raises(NoData, match="GPS"):
        drone.get_global_position()


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


def test_bad_commands_raise_and_send_nothing(drone, bridge):
    t0 = time.monotonic()
    for call in (
        lambda: drone.set_cmd_vel(vx=float("nan")),
        lambda: drone.set_cmd_pos(z=float("inf")),
        lambda: drone.set_cmd_mix(vx="1"),
        lambda: drone.set_cmd_vel(az=True),
        lambda: drone.set_cmd_vel(stamp=float("nan")),
    ):
        with pytest.raises(InvalidArgument):
            call()
    with pytest.raises(ValueError):
        drone.set_cmd_pos(x=None)
    with pytest.raises(TypeError):
        drone.set_cmd_pos(y=[1])
    assert drone.setpoints_sent == 0
    # nothing went on the wire: what the bridge receives is only the next good setpoint
    drone.set_cmd_vel(vx=0.25)
    wait_for(lambda: bridge.setpoints_since(t0), 10, what="the good setpoint")
    drone.stop_commanding()
    assert {(m.velocity.x, m.type_mask) for m in bridge.setpoints_since(t0)} == {(0.25, 1991)}


def test_takeoff_streams_then_offboard_then_arms_and_returns_at_altitude(drone, bridge):
    drone.takeoff(h=1.0, timeout=20)
    assert drone.get_position()[2] >= 0.9
    assert bridge.calls[:2] == ["set_mode OFFBOARD", "arming True"]
    first = bridge.setpoints[0][1]
    assert first.type_mask == MASK_POSITION and first.position.z == 0.0  # hold on the ground
    assert drone.commanding is not None and drone.commanding.position.z == pytest.approx(1.0)
    wait_for(drone.is_flying, 10, what="in air")
    calls = len(bridge.calls)
    drone.takeoff(h=1.0)  # idempotent: flying -> returns at once, no service call
    assert len(bridge.calls) == calls
    drone.land(timeout=20)
    assert bridge.calls[-1] == "land"
    assert drone.get_landed_state() == LANDED_STATE_ON_GROUND
    assert not drone.get_state().armed
    assert drone.commanding is None  # land stops the stream
    # the fake has no GPS: land asks to land "here" (NaN latitude/longitude)
    assert math.isnan(bridge.land_requests[-1].latitude)
    assert math.isnan(bridge.land_requests[-1].longitude)


@pytest.mark.parametrize(
    ("autopilot", "expected"),
    [
        ("ardupilotmega", ["set_mode GUIDED", "arming True", "takeoff 1"]),
        ("tello", ["takeoff 1"]),
    ],
)
def test_takeoff_sequence_follows_the_autopilot(router, autopilot, expected):
    fake = FakeBridge(router, autopilot=autopilot)
    try:
        with DroneWrapper("drone", router, timeout=10) as drone:
            drone.takeoff(h=1.0, timeout=20)
            assert fake.calls == expected
            assert drone.get_position()[2] >= 0.9
            assert drone.commanding is None  # these autopilots hold by themselves
    finally:
        fake.close()


def test_takeoff_refusal_carries_the_autopilot_reason(drone, bridge):
    bridge.refuse_arming = "Arming denied: preflight checks failed"
    with pytest.raises(CommandRefused) as info:
        drone.takeoff(h=1.0, timeout=10)
    assert "preflight checks failed" in str(info.value)
    assert info.value.result == MAV_RESULT_DENIED
    assert drone.commanding is None  # no stream left behind after a refusal
    wait_for(lambda: drone.status_texts, 10, what="status text")
    assert drone.status_texts[-1].text == bridge.refuse_arming


def test_takeoff_timeout_names_the_altitude(drone, bridge):
    with pytest.raises(Timeout, match=r"altitude 5\.00 m not reached"):
        drone.takeoff(h=5.0, timeout=0.5)


def test_services_arm_mode_params(drone, bridge):
    drone.arm()
    wait_for(lambda: drone.get_state().armed, 10, what="armed")
    drone.disarm()
    with pytest.raises(CommandRefused, match="unknown mode WHATEVER"):
        drone.set_mode("WHATEVER")
    with pytest.raises(InvalidArgument):
        drone.set_mode("")
    assert drone.param_get("MPC_XY_VEL_MAX") == 12.0
    assert drone.param_set("MPC_XY_VEL_MAX", 3) == 3
    assert bridge.params["MPC_XY_VEL_MAX"].integer == 3
    assert drone.param_set("MPC_XY_VEL_MAX", 2.5) == 2.5
    with pytest.raises(CommandRefused, match="no parameter NOPE"):
        drone.param_get("NOPE")
    with pytest.raises(InvalidArgument):
        drone.param_set("MPC_XY_VEL_MAX", float("nan"))


def test_images_are_bgr_arrays_of_the_newest_frame(drone, bridge):
    with pytest.raises(NoData, match="cam_frontal/image_raw"):
        drone.get_frontal_image()
    with pytest.raises(Timeout, match="cam_ventral"):
        drone.wait_for_image("ventral", timeout=0.3)
    frame = np.zeros((6, 8, 3), np.uint8)
    frame[..., 2] = 255  # red in BGR
    bridge.publish_image(frame, stamp=1.7e9)
    img = drone.wait_for_image("frontal", timeout=10)
    assert img.shape == (6, 8, 3) and img[0, 0].tolist() == [0, 0, 255]
    img[:] = 0  # writable, and a copy: the next get is unchanged
    again, stamp = drone.get_image("frontal", with_stamp=True)
    assert again[0, 0].tolist() == [0, 0, 255] and stamp == 1.7e9
    with pytest.raises(InvalidArgument):
        drone.get_image("rear")


def test_context_manager_stops_commanding_on_exception(router, bridge):
    with (
        pytest.raises(RuntimeError, match="app bug"),
        DroneWrapper("drone", router, timeout=10) as drone,
    ):
        drone.set_cmd_vel(vx=0.5)
        raise RuntimeError("app bug")
    sent = drone.setpoints_sent
    bridge.wait_quiet()
    assert all(m.header.seq < sent for _, m in bridge.setpoints)  # none after the exit


def test_land_on_exit_lands_when_flying(router, bridge):
    with DroneWrapper("drone", router, timeout=10, land_on_exit=True) as drone:
        drone.takeoff(h=0.6, timeout=20)
        wait_for(drone.is_flying, 10, what="in air")
    assert bridge.calls[-1] == "land"
    assert not bridge.armed


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


def test_embedding_on_an_existing_session(router, bridge):
    node = client_node(router, name="embedder")
    try:
        drone = DroneWrapper(name="drone", session=node.session, cameras=(), wait=False)
        drone.wait_for_connection(10)
        drone.set_cmd_vel(vz=0.1)
        wait_for(lambda: bridge.setpoints, 10, what="setpoint from the embedded SDK")
        drone.close()
        assert not node.session.is_closed()  # the owner's session stays open
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


def test_position_setpoint_without_z_or_yaw_keeps_altitude_and_heading(drone, bridge):
    bridge.z = 1.7
    wait_for(lambda: drone.get_position()[2] == pytest.approx(1.7), 10, what="pose at 1.7 m")
    drone.set_cmd_pos(1.0, 0.0)  # the student's call: no dive to z = 0, no turn east
    assert drone.commanding.position.z == pytest.approx(1.7)
    assert drone.commanding.yaw == pytest.approx(0.0)
    drone.set_cmd_pos(2.0, 1.0, 3.0, 0.5)
    drone.set_cmd_pos(1.0, 0.0)  # keeps what is being commanded, not the current pose
    assert (drone.commanding.position.z, drone.commanding.yaw) == pytest.approx((3.0, 0.5))
    drone.set_cmd_mix(vx=0.5)
    assert drone.commanding.position.z == pytest.approx(3.0)
    drone.stop_commanding()
    drone.set_cmd_mix(vx=0.5)
    assert drone.commanding.position.z == pytest.approx(1.7)
    drone.stop_commanding()


def test_degrees_by_mistake_are_refused_with_the_conversion(drone, bridge):
    t0 = time.monotonic()
    with pytest.raises(InvalidArgument, match=r"radians.*math\.radians\(90\) = 1\.571"):
        drone.set_cmd_pos(0.0, 0.0, 2.0, 90)
    with pytest.raises(InvalidArgument, match="rad/s"):
        drone.set_cmd_vel(az=45)
    drone.set_cmd_vel(az=-6.0)  # within a turn per second: accepted
    drone.stop_commanding()
    assert all(sp.yaw_rate == -6.0 for sp in bridge.setpoints_since(t0))


def test_grounded_setpoints_and_takeoff_while_flying_say_so(drone, bridge, caplog):
    with caplog.at_level(logging.INFO, logger="dronewrapper"):
        drone.set_cmd_vel(vx=1.0)
        drone.set_cmd_vel(vx=1.0)
        drone.stop_commanding()
        grounded = [r for r in caplog.records if "nothing moves until takeoff()" in r.message]
        assert len(grounded) == 1  # once, not at every call
        drone.takeoff(h=1.0, timeout=20)
        messages = [r.message for r in caplog.records]
        assert any("armed in OFFBOARD, climbing" in m for m in messages)
        assert any("takeoff: reached 1.00 m" in m for m in messages)
        wait_for(drone.is_flying, 10, what="in air")
        drone.takeoff(h=4.0)
        assert any(
            "already flying" in r.message and "does nothing" in r.message
            for r in caplog.records
            if r.levelno == logging.WARNING
        )
        drone.land(timeout=20)
        assert any("on the ground and disarmed" in r.message for r in caplog.records)


def test_arming_refused_in_offboard_without_a_stream_names_the_real_cause(drone, bridge):
    bridge.mode = "OFFBOARD"
    bridge.refuse_arming = "Resolve system health failures first"
    wait_for(lambda: drone.get_state().mode == "OFFBOARD", 10, what="OFFBOARD state")
    with pytest.raises(CommandRefused, match="no setpoint is being streamed"):
        drone.arm()
    bridge.mode = "POSCTL"
    wait_for(lambda: drone.get_state().mode == "POSCTL", 10, what="POSCTL state")
    with pytest.raises(CommandRefused) as info:
        drone.arm()
    assert "setpoint" not in str(info.value)


def test_cameras_are_subscribed_only_when_read(drone, bridge):
    """A program that never reads a frame never pulls one across the network."""
    publisher = bridge.pub_image._pub
    time.sleep(0.5)
    assert not publisher.matching_status.matching
    assert not drone.compressed_images  # the router is on this machine: raw frames
    with pytest.raises(NoData, match="no image received yet"):
        drone.get_frontal_image()
    wait_for(lambda: publisher.matching_status.matching, 10, what="a camera subscriber")


def test_explicitly_refused_cameras_stay_refused(router, bridge):
    with (
        DroneWrapper("drone", router, timeout=10, cameras=()) as drone,
        pytest.raises(NoData, match="was not requested"),
    ):
        drone.get_frontal_image()


def test_every_getter_says_its_age_and_stale_telemetry_is_warned_once(drone, bridge, caplog):
    assert drone.age("position") < 1.0 and drone.age("battery") < 1.0
    assert drone.age("frontal_image") == float("inf")
    with pytest.raises(InvalidArgument, match="use one of"):
        drone.age("altitude")
    bridge.paused = True
    wait_for(lambda: drone.age("position") > 0.6, 10, what="the pose to go stale")
    with caplog.at_level(logging.WARNING, logger="dronewrapper"):
        drone.get_position()
        drone.get_position()
    stale = [r for r in caplog.records if "stale after 0.5 s" in r.message]
    assert len(stale) == 1 and "drone/mavros/local_position/pose" in stale[0].message
    bridge.paused = False
