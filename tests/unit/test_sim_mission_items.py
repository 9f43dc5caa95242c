"""The simulator flies the items PX4 takes (sim/dronewrapper_sim/px4/mission.py): a speed
change sets the speed of the legs after it, camera/gimbal/ROI items are taken and skipped
with a note, AMSL altitudes are AMSL. Ground truth from the vehicle's state; time injected."""

from __future__ import annotations

import math

from pymavlink.dialects.v20 import common as mavlink

from dronewrapper_sim.px4.autopilot import Autopilot, AutopilotConfig
from dronewrapper_sim.px4.mission import MISSION
from dronewrapper_sim.px4.modes import Mode

DT = 1.0 / 250.0
HOME_AMSL = 488.0


def upload(ap: Autopilot, items: list[tuple[int, int, float, float, float, float]]) -> int:
    """Upload (command, frame, param1, param2, east m, north m / z) items as a GCS would;
    returns the final MISSION_ACK result. Positions are metres from the local origin, z the
    item's altitude in its frame."""
    store = ap.missions
    header = mavlink.MAVLink_header(0, 0, 0, 255, 190)
    count = mavlink.MAVLink_mission_count_message(1, 1, len(items), MISSION)
    count._header = header
    replies = store.handle(count, ap.time_s)
    for seq, (command, frame, p1, p2, east, north, z) in enumerate(items):
        lat, lon = ap.geodetic(east, north)
        msg = mavlink.MAVLink_mission_item_int_message(
            1, 1, seq, frame, command, 0, 1, p1, p2, 0, math.nan,
            round(lat * 1e7), round(lon * 1e7), z, MISSION,
        )  # fmt: skip
        msg._header = header
        replies = store.handle(msg, ap.time_s)
    (ack,) = replies
    return ack.type


def airborne(ap: Autopilot, z: float = 5.0) -> None:
    """Armed and hovering at ``z`` m over the origin."""
    cmd = ap.commander
    assert cmd.arm(ap.time_s, ap.state) == mavlink.MAV_RESULT_ACCEPTED
    cmd.takeoff(ap.time_s, ap.state, z)
    run(ap, 12.0)
    assert abs(ap.state.z - z) < 0.5


def run(ap: Autopilot, seconds: float, watch=None) -> None:
    for _ in range(round(seconds / DT)):
        ap.step(DT)
        if watch is not None:
            watch(ap)


def top_speeds(ap: Autopilot, seconds: float, west: float, east: float) -> tuple[float, float]:
    """The largest horizontal ground speed (m/s) west of ``west`` and east of ``east`` (x m)."""
    top = [0.0, 0.0]

    def watch(ap: Autopilot) -> None:
        speed = math.hypot(ap.state.vx, ap.state.vy)
        if ap.state.x < west:
            top[0] = max(top[0], speed)
        elif ap.state.x > east:
            top[1] = max(top[1], speed)

    run(ap, seconds, watch)
    return top[0], top[1]


WP, SPEED, REL = mavlink.MAV_CMD_NAV_WAYPOINT, mavlink.MAV_CMD_DO_CHANGE_SPEED, 3


def test_a_speed_change_flies_the_next_leg_at_that_speed():
    ap = Autopilot(AutopilotConfig(params={"MPC_XY_CRUISE": 5.0}))
    airborne(ap)
    items = [
        (WP, REL, 0, 0, 60.0, 0.0, 5.0),  # 60 m east at the default 5 m/s
        (SPEED, 2, 1, 10.0, 0.0, 0.0, 0.0),  # ground speed 10 m/s from here on
        (WP, REL, 0, 0, 160.0, 0.0, 5.0),  # 100 m further east
    ]
    assert upload(ap, items) == mavlink.MAV_MISSION_ACCEPTED
    assert ap.commander.set_mode(Mode.MISSION, ap.time_s, ap.state) == mavlink.MAV_RESULT_ACCEPTED
    slow, fast = top_speeds(ap, 40.0, west=55.0, east=70.0)
    assert math.hypot(ap.state.x - 160.0, ap.state.y) < 2.0  # the mission was flown
    assert slow < 5.5  # MPC_XY_CRUISE before the change
    assert 9.0 < fast < 10.5  # up to the 10 m/s asked, not the 5 m/s default


def test_a_speed_above_the_limit_is_capped_and_minus_two_restores_the_default():
    ap = Autopilot(AutopilotConfig(params={"MPC_XY_CRUISE": 5.0, "MPC_XY_VEL_MAX": 8.0}))
    airborne(ap)
    items = [
        (SPEED, 2, 0, 20.0, 0.0, 0.0, 0.0),  # above MPC_XY_VEL_MAX: 8 m/s
        (WP, REL, 0, 0, 80.0, 0.0, 5.0),
        (SPEED, 2, 1, -2.0, 0.0, 0.0, 0.0),  # back to the default
        (WP, REL, 0, 0, 160.0, 0.0, 5.0),
    ]
    assert upload(ap, items) == mavlink.MAV_MISSION_ACCEPTED
    ap.commander.set_mode(Mode.MISSION, ap.time_s, ap.state)
    capped, default = top_speeds(ap, 45.0, west=75.0, east=90.0)
    assert 7.0 < capped < 8.5
    assert default < 5.5


def test_camera_gimbal_and_roi_items_are_taken_and_skipped_with_a_note():
    ap = Autopilot()
    airborne(ap)
    skipped = [
        mavlink.MAV_CMD_DO_MOUNT_CONTROL,
        mavlink.MAV_CMD_IMAGE_START_CAPTURE,
        mavlink.MAV_CMD_SET_CAMERA_MODE,
        mavlink.MAV_CMD_DO_SET_CAM_TRIGG_DIST,
        mavlink.MAV_CMD_DO_GRIPPER,
        mavlink.MAV_CMD_DO_SET_ROI_LOCATION,
        mavlink.MAV_CMD_DO_SET_ROI_NONE,
    ]
    items = [(command, 2, 0, 0, 0.0, 0.0, 0.0) for command in skipped]
    items.append((WP, REL, 0, 0, 10.0, 0.0, 5.0))
    assert upload(ap, items) == mavlink.MAV_MISSION_ACCEPTED
    ap.commander.set_mode(Mode.MISSION, ap.time_s, ap.state)
    run(ap, 10.0)
    assert math.hypot(ap.state.x - 10.0, ap.state.y) < 2.5  # NAV_ACC_RAD 2 m
    texts = [t.text for t in ap.commander.drain_texts()]
    assert "Mission item 0: DO_MOUNT_CONTROL skipped (no camera, gimbal or gripper)" in texts
    assert sum("skipped" in t for t in texts) == len(skipped)


def test_a_spline_waypoint_is_refused_as_px4_refuses_it():
    ap = Autopilot()
    items = [
        (WP, REL, 0, 0, 5.0, 0.0, 5.0),
        (mavlink.MAV_CMD_NAV_SPLINE_WAYPOINT, REL, 0, 0, 9, 0, 5),
    ]
    assert upload(ap, items) == mavlink.MAV_MISSION_UNSUPPORTED


def test_an_amsl_item_flies_at_its_amsl_altitude():
    ap = Autopilot()
    airborne(ap, 5.0)
    items = [(WP, 0, 0, 0, 10.0, 0.0, HOME_AMSL + 8.0)]  # frame 0: 8 m above the 488 m home
    assert upload(ap, items) == mavlink.MAV_MISSION_ACCEPTED
    ap.commander.set_mode(Mode.MISSION, ap.time_s, ap.state)
    top = [0.0]
    run(ap, 15.0, lambda ap: top.__setitem__(0, max(top[0], ap.state.z)))
    assert abs(ap.state.z - 8.0) < 0.5 and top[0] < 9.0
    assert math.hypot(ap.state.x - 10.0, ap.state.y) < 2.5  # NAV_ACC_RAD 2 m
