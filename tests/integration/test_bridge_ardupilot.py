"""The paper's listing against a scripted ArduCopter that behaves as real ArduCopter SITL did
(issue 21): position targets in GUIDED override its take-off, and it disarms itself 10 s after
arming if it never left the ground. Bridge in-process, real UDP, real Zenoh, the real SDK.

Against real ArduCopter SITL the same flights are in tests/sitl (opt-in).
"""

from __future__ import annotations

import time

import pytest
from test_bridge_node import make_rig

from dronewrapper import DroneWrapper
from dronewrapper.msgs import registry
from dronewrapper.msgs.geometry import Point
from dronewrapper.msgs.mavros import FRAME_LOCAL_NED, MASK_POSITION, PositionTarget
from support import wait_for

GUIDED, LOITER, LAND = 4, 5, 9


@pytest.fixture
def ardu_rig(router):
    yield from make_rig(router, autopilot=3)


def test_paper_listing_takes_off_lands_on_arducopter(ardu_rig, router):
    """takeoff(h=2.5) arms and sends NAV_TAKEOFF ~20 ms after GUIDED: before the fix the
    bridge's 3 s 'priming' hold at the ground overrode the take-off and ArduCopter disarmed."""
    bridge, fake, _user = ardu_rig
    with DroneWrapper("drone", router, timeout=20, cameras=()) as drone:
        drone.takeoff(h=2.5, timeout=20)
        (takeoff,) = fake.commands_named(22)
        assert takeoff.param7 == 2.5 and not fake.takeoff_overridden
        assert fake.setpoints == [], "nothing may be streamed into ArduCopter's take-off"
        assert drone.get_state().mode == "GUIDED" and drone.get_state().armed
        drone.set_cmd_vel(az=1)  # the listing: spin at 1 rad/s
        wait_for(lambda: fake.setpoints, 5, what="the yaw-rate stream")
        time.sleep(1.0)
        drone.land(timeout=30)
    assert fake.custom_mode == LAND and not fake.armed
    yaw_rates = {round(m.yaw_rate, 3) for _, m in fake.setpoints if m.type_mask != MASK_POSITION}
    assert yaw_rates == {-1.0}  # ENU +1 rad/s (counter-clockwise) is NED -1 rad/s
    assert bridge.core.failsafe.state == ""


def test_scripted_arducopter_disarms_when_its_take_off_is_overridden(ardu_rig):
    """The scripted peer itself: the failure of issue 21 is reproducible with it (a hold at
    the ground after NAV_TAKEOFF: no climb, 'Disarming motors' after disarm_delay)."""
    bridge, fake, user = ardu_rig
    fake.disarm_delay = 2.0  # 10 s on ArduCopter; shorter to keep the test short
    texts: list[str] = []
    user.subscribe(registry.STATUSTEXT, lambda t: texts.append(t.text))
    fake.custom_mode, fake.armed, fake.armed_at = GUIDED, True, time.monotonic()
    wait_for(lambda: bridge.core.failsafe.mode == "GUIDED", 10)
    fake.climb_to = 2.5  # as after NAV_TAKEOFF
    ground = PositionTarget(
        coordinate_frame=FRAME_LOCAL_NED, type_mask=MASK_POSITION, position=Point(z=0.0)
    )
    user.publisher(registry.SETPOINT_RAW_LOCAL).put(ground)  # a hold at the ground
    wait_for(lambda: "Disarming motors" in texts, 10, what="ArduCopter's disarm")
    assert fake.takeoff_overridden and fake.position_ned[2] > -0.2


@pytest.mark.parametrize("autopilot", [3, 12], ids=["arducopter", "px4"])
def test_integer_parameter_zero_is_int_zero(router, autopilot):
    """Issue 21: an integer parameter equal to 0 came back as 0.0 (on any autopilot).
    ArduPilot 4.8's names (ARMING_SKIPCHK was ARMING_CHECK, MAV_SYSID was SYSID_THISMAV)."""
    rig = make_rig(router, autopilot=autopilot)
    _bridge, fake, _user = next(rig)
    try:
        fake.params.update({"ARMING_SKIPCHK": (0, 6), "MAV_SYSID": (1, 6), "WP_SPD": (0.0, 9)})
        with DroneWrapper("drone", router, timeout=20, cameras=()) as drone:
            zero = drone.param_get("ARMING_SKIPCHK")
            assert zero == 0 and isinstance(zero, int)
            assert drone.param_get("MAV_SYSID") == 1
            real_zero = drone.param_get("WP_SPD")
            assert real_zero == 0.0 and isinstance(real_zero, float)
            written = drone.param_set("ARMING_SKIPCHK", 0)
            assert written == 0 and isinstance(written, int)
    finally:
        rig.close()
