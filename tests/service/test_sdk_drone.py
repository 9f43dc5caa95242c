"""DroneWrapper's logic on the fake bus, in bus time (tests/bus_autopilot.py SdkRig).

Take-off and landing (one request each: the bridge flies them), services and the errors they
raise, setpoints, getters and their ages: a BusAutopilot serves the bridge's keys, and the
wrapper's blocking calls move the bus time instead of sleeping, so every duration here is
exact however loaded the machine. The SDK's Zenoh wiring (the constructor's waits and
diagnoses, the stream's rate on the wire, sessions, cameras pulled only when read) is tested on
a real router in tests/integration/test_sdk_zenoh.py.
"""

from __future__ import annotations

import logging
from collections.abc import Iterator

import numpy as np
import pytest
from bus_autopilot import TELEMETRY_PERIOD_S, SdkRig

from dronewrapper import (
    CommandRefused,
    DroneWrapper,
    InvalidArgument,
    NoData,
    NotConnected,
    Timeout,
)
from dronewrapper.msgs import registry
from dronewrapper.msgs.link import LinkStatus
from dronewrapper.msgs.mavros import (
    LANDED_STATE_ON_GROUND,
    MASK_MIXED,
    MASK_VELOCITY,
    ParamGetResult,
)
from dronewrapper.msgs.sensor import Image
from dronewrapper.msgs.std import Header
from dronewrapper.runtime import ServiceTimeout
from dronewrapper.runtime.fake import FakeNode


@pytest.fixture
def rig() -> Iterator[SdkRig]:
    rig = SdkRig({"x": 1.0})
    yield rig
    rig.close()


def sent(rig: SdkRig) -> list:
    """Every setpoint the wrapper published, oldest first."""
    return [msg for _, msg in rig.pilot.setpoints()]


def names(rig: SdkRig) -> list[str]:
    return [name for _, name in rig.pilot.calls]


def test_getters_return_the_newest_values_at_once(rig):
    drone = rig.drone
    assert drone.get_position().tolist() == [1.0, 0.0, 0.0]
    assert drone.wait_for(drone.get_position, 1, "position").shape == (3,)  # arrays count
    assert drone.wait_for_altitude(0.0, timeout=1)[0] == 1.0
    start = rig.bus.clock()
    with pytest.raises(Timeout, match=r"altitude 3\.00 m .*now z=0\.00 m"):
        drone.wait_for_altitude(3.0, timeout=0.2)
    assert rig.bus.clock() - start == pytest.approx(0.2, abs=0.021)  # waited in bus time
    assert drone.get_orientation().tolist() == [0.0, 0.0, 0.0]
    assert drone.get_yaw_rate() == 0.25
    assert drone.get_velocity().tolist() == [0.0, 0.0, 0.0]
    assert drone.get_velocity_local().shape == (3,)
    assert drone.get_landed_state() == LANDED_STATE_ON_GROUND
    state = drone.get_state()
    assert state.connected and state.autopilot == "px4" and drone.is_connected()
    assert drone.get_battery() == pytest.approx(0.8)
    with pytest.raises(NoData, match="GPS"):
        drone.get_global_position()


def test_the_app_sees_how_full_the_autopilot_link_is(rig):
    drone = rig.drone
    with pytest.raises(NoData, match="bridge/link"):
        drone.get_link()  # a bridge that reports no link (the Tello's)
    bridge = FakeNode("bridge_link", rig.bus).publisher(registry.LINK_STATUS)
    bridge.put(LinkStatus(kind="serial", baud=57600, capacity=5760.0, received_rate=5414.0,
                          sent_rate=1800.0, load=0.94))  # fmt: skip
    link = drone.get_link()
    assert link.load == 0.94
    assert link.describe().startswith("link 94 % full (serial 57600 baud: 5.4 / 1.8 kB/s")


def test_setpoints_carry_their_mask_frame_and_stamp_and_stop_on_request(rig):
    drone = rig.drone
    drone.set_cmd_vel(az=1)
    first = sent(rig)[0]  # out at once, before any repetition
    assert (first.type_mask, first.coordinate_frame, first.yaw_rate) == (MASK_VELOCITY, 8, 1.0)
    drone.set_cmd_mix(vx=0.5, z=2.0, az=0.1, stamp=1.7e9)
    mixed = sent(rig)[-1]
    assert mixed.type_mask == MASK_MIXED and mixed.position.z == 2.0 and mixed.velocity.x == 0.5
    assert mixed.header.stamp == 1.7e9
    drone.stop_commanding()
    assert drone.commanding is None


def test_bad_commands_raise_and_send_nothing(rig):
    drone = rig.drone
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
    assert drone.setpoints_sent == 0 and sent(rig) == []
    drone.set_cmd_vel(vx=0.25)  # what goes out is only the next good setpoint
    drone.stop_commanding()
    assert {(m.velocity.x, m.type_mask) for m in sent(rig)} == {(0.25, MASK_VELOCITY)}


def test_a_call_nobody_answers_is_a_timeout_naming_the_key():
    rig = SdkRig({"absent": ["flight_takeoff"]})
    key = registry.FLIGHT_TAKEOFF.key("drone")
    with pytest.raises(Timeout, match=f"takeoff: no reply from {key} within 2 s"):
        rig.drone.takeoff(h=1.0, timeout=30)  # 40 s allowed; no server took it for 2 s
    rig.close()


def test_a_reply_later_than_the_timeout_is_a_timeout_not_a_refusal(rig):
    """Zenoh ends such a query with its own error (a ServiceTimeout, a kind of
    ServiceUnavailable): the user is told the bridge is slow, never "refused"."""

    def slow(_request) -> ParamGetResult:
        raise ServiceTimeout("no reply from drone/mavros/param/get within 0.5 s (Zenoh ...)")

    rig.pilot.node.serve(registry.PARAM_GET, slow)
    with pytest.raises(Timeout, match=r"param_get P: no reply from .* within 0\.5 s") as caught:
        rig.drone.param_get("P", timeout=0.5)
    assert not isinstance(caught.value, CommandRefused)


def test_a_bridge_gone_silent_is_not_connected(rig):
    rig.bus.clock.advance_to(rig.bus.clock() + 5.0)  # no State for 5 s
    assert not rig.drone.is_connected()
    with pytest.raises(NotConnected, match="takeoff: "):
        rig.drone.takeoff(h=1.0)
    assert rig.pilot.calls == []


def test_services_arm_mode_params(rig):
    drone, pilot = rig.drone, rig.pilot
    drone.arm()
    rig.run(0.05)
    assert drone.get_state().armed
    drone.disarm()
    pilot.refuse["set_mode"] = "unknown mode WHATEVER"
    with pytest.raises(CommandRefused, match="unknown mode WHATEVER"):
        drone.set_mode("WHATEVER")
    with pytest.raises(InvalidArgument):
        drone.set_mode("")
    assert drone.param_get("MPC_XY_VEL_MAX") == 12.0
    assert drone.param_set("MPC_XY_VEL_MAX", 3) == 3
    assert pilot.params["MPC_XY_VEL_MAX"].integer == 3
    assert drone.param_set("MPC_XY_VEL_MAX", 2.5) == 2.5
    with pytest.raises(CommandRefused, match="no parameter NOPE"):
        drone.param_get("NOPE")
    with pytest.raises(InvalidArgument):
        drone.param_set("MPC_XY_VEL_MAX", float("nan"))


def test_images_are_bgr_arrays_of_the_newest_frame(rig):
    drone = rig.drone
    with pytest.raises(NoData, match="cam_frontal/image_raw"):
        drone.get_frontal_image()  # subscribes now (cameras are lazy)
    with pytest.raises(Timeout, match="cam_ventral"):
        drone.wait_for_image("ventral", timeout=0.01)
    camera = FakeNode("camera", rig.bus).publisher(registry.IMAGE_RAW, camera="cam_frontal")
    frame = np.zeros((6, 8, 3), np.uint8)
    frame[..., 2] = 255  # red in BGR
    camera.put(Image(header=Header(stamp=1.7e9), height=6, width=8, step=24, data=frame.tobytes()))
    img = drone.wait_for_image("frontal", timeout=10)
    assert img.shape == (6, 8, 3) and img[0, 0].tolist() == [0, 0, 255]
    img[:] = 0  # writable, and a copy: the next get is unchanged
    again, stamp = drone.get_image("frontal", with_stamp=True)
    assert again[0, 0].tolist() == [0, 0, 255] and stamp == 1.7e9
    with pytest.raises(InvalidArgument):
        drone.get_image("rear")


def test_explicitly_refused_cameras_stay_refused():
    rig = SdkRig(cameras=())
    with pytest.raises(NoData, match="was not requested"):
        rig.drone.get_frontal_image()
    rig.close()


def test_context_manager_stops_commanding_on_exception(rig):
    with pytest.raises(RuntimeError, match="app bug"), rig.drone as drone:
        drone.set_cmd_vel(vx=0.5)
        raise RuntimeError("app bug")
    assert drone.commanding is None
    with pytest.raises(NotConnected, match="closed"):
        drone.set_cmd_vel(vx=0.5)


def test_land_on_exit_lands_when_flying():
    rig = SdkRig(land_on_exit=True)
    with rig.drone as drone:
        drone.takeoff(h=0.6, timeout=20)
        assert drone.is_flying()
    assert names(rig)[-1] == "flight_land" and not rig.pilot.armed


def test_position_setpoint_without_z_or_yaw_keeps_altitude_and_heading(rig):
    drone = rig.drone
    rig.pilot.z = 1.7
    rig.run(0.05)
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


def test_degrees_by_mistake_are_refused_with_the_conversion(rig):
    drone = rig.drone
    with pytest.raises(InvalidArgument, match=r"radians.*math\.radians\(90\) = 1\.571"):
        drone.set_cmd_pos(0.0, 0.0, 2.0, 90)
    with pytest.raises(InvalidArgument, match="rad/s"):
        drone.set_cmd_vel(az=45)
    drone.set_cmd_vel(az=-6.0)  # within a turn per second: accepted
    drone.stop_commanding()
    assert sent(rig) and all(sp.yaw_rate == -6.0 for sp in sent(rig))


def test_grounded_setpoints_and_takeoff_while_flying_say_so(rig, caplog):
    drone = rig.drone
    with caplog.at_level(logging.INFO, logger="dronewrapper"):
        drone.set_cmd_vel(vx=1.0)
        drone.set_cmd_vel(vx=1.0)
        drone.stop_commanding()
        grounded = [r for r in caplog.records if "nothing moves until takeoff()" in r.message]
        assert len(grounded) == 1  # once, not at every call
        drone.takeoff(h=1.0, timeout=20)
        messages = [r.message for r in caplog.records]
        assert any("takeoff: drone 'drone' to 1.00 m" in m for m in messages)
        assert any("takeoff: drone 'drone': took off" in m for m in messages)
        drone.takeoff(h=4.0)
        assert any(
            "already flying" in r.message for r in caplog.records if r.levelno == logging.WARNING
        )
        drone.land(timeout=20)
        assert any("on the ground and disarmed" in r.message for r in caplog.records)


def test_arming_refused_in_offboard_without_a_stream_names_the_real_cause(rig):
    rig.pilot.mode = "OFFBOARD"
    rig.pilot.refuse["arming"] = "Resolve system health failures first"
    rig.run(0.05)
    with pytest.raises(CommandRefused, match="no setpoint is being streamed"):
        rig.drone.arm()
    rig.pilot.mode = "POSCTL"
    rig.run(0.05)
    with pytest.raises(CommandRefused) as info:
        rig.drone.arm()
    assert "setpoint" not in str(info.value)


def test_every_getter_says_its_age_and_stale_telemetry_is_warned_once(rig, caplog):
    drone = rig.drone
    fresh = drone.age("position")
    assert fresh <= TELEMETRY_PERIOD_S + 1e-6 and drone.age("battery") == pytest.approx(fresh)
    assert drone.age("frontal_image") == float("inf")
    with pytest.raises(InvalidArgument, match="use one of"):
        drone.age("altitude")
    rig.bus.clock.advance_to(rig.bus.clock() + 0.7)  # the link stalls: nothing for 0.7 s
    assert drone.age("position") == pytest.approx(fresh + 0.7)
    with caplog.at_level(logging.WARNING, logger="dronewrapper"):
        drone.get_position()
        drone.get_position()
    stale = [r for r in caplog.records if "stale after 0.5 s" in r.message]
    assert len(stale) == 1 and "drone/mavros/local_position/pose" in stale[0].message


def test_an_observer_on_a_shared_node_is_refused_before_sending(tmp_path, monkeypatch):
    """A node opened elsewhere (a Fleet's) carries the identity in its options: an observer's
    certificate refuses the command at the call, and nothing reaches the bridge."""
    from dronewrapper.runtime.options import ZenohOptions
    from dronewrapper.security.keystore import KeyStore

    store = KeyStore(tmp_path / "keys")
    store.init()
    store.issue("olga", "observer")
    monkeypatch.setenv("DRONEWRAPPER_KEYS", str(store.root))
    rig = SdkRig({"x": 1.0}, open_drone=False)
    rig.node.options = ZenohOptions(connect=["tls/192.168.1.10:7448"], identity="olga")
    rig.drone = DroneWrapper("drone", **rig.options())
    with pytest.raises(CommandRefused, match=r"not permitted for role observer.*not sent"):
        rig.drone.arm()
    assert names(rig) == []
    rig.close()
