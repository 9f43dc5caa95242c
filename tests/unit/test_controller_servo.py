"""The servo state machine: tracking, hover on stale detections or a fresh loss, search, limits."""

from __future__ import annotations

import msgspec
import pytest

from dronewrapper.msgs.control import CONTROLLER_HOVER, CONTROLLER_SEARCH, CONTROLLER_TRACKING
from dronewrapper.msgs.std import Header
from dronewrapper.msgs.vision import BoundingBox2D, Detection2D, Detections
from dronewrapper_controller.config import FollowColorConfig, FollowPersonConfig, ServoConfig
from dronewrapper_controller.pid import PidGains
from dronewrapper_controller.servo import Servo, pick_target

W, H = 320, 240


def box(cx, cy, w, h, *, radius=0.0, id_=""):
    bbox = BoundingBox2D.at(cx, cy, w, h)
    return Detection2D(bbox=bbox, circle_radius=radius, id=id_)


def frame(stamp, *dets, target_id="", detector="color"):
    return Detections(
        header=Header(stamp=stamp),
        detections=list(dets),
        image_width=W,
        image_height=H,
        detector=detector,
        target_id=target_id,
    )


def colour_config(**kw) -> ServoConfig:
    base = dict(
        mode="follow_color",
        detection_timeout=0.5,
        lost_hold=0.0,
        search_delay=2.0,
        search_yaw_rate=0.3,
        follow_color=FollowColorConfig(
            target_radius=10, vx=PidGains(kp=-0.5, out_limit=1.0, d_tau=0.0)
        ),
        vz=PidGains(kp=0.02, out_limit=0.5),
        yaw_rate=PidGains(kp=0.005, out_limit=0.8),
    )
    base.update(kw)
    return ServoConfig(**base)


def test_tracking_signs_blob_far_left_high():
    """Small blob, up and left: go forward, climb, turn left (all positive in FLU)."""
    servo = Servo(colour_config())
    cmd = servo.step(0.0, frame(100.0, box(60, 40, 10, 10, radius=5)), age=0.01)
    assert cmd.state == CONTROLLER_TRACKING and cmd.target_visible
    assert cmd.vx == pytest.approx(0.25)  # -0.5 * (5 - 10) / 10
    assert cmd.vz == pytest.approx(0.5)  # 0.02 * 80 = 1.6 -> saturated at 0.5
    assert cmd.yaw_rate == pytest.approx(0.5)  # 0.005 * 100
    assert cmd.source_stamp == 100.0


def test_tracking_signs_blob_close_right_low():
    servo = Servo(colour_config())
    cmd = servo.step(0.0, frame(5.0, box(200, 150, 60, 60, radius=30)), age=0.0)
    assert cmd.vx == pytest.approx(-1.0)  # too close: back off, saturated
    assert cmd.vz == pytest.approx(-0.5)  # 0.02 * -30 = -0.6, saturated
    assert cmd.yaw_rate == pytest.approx(-0.2)


def test_centred_at_target_radius_commands_nothing():
    servo = Servo(colour_config())
    cmd = servo.step(0.0, frame(1.0, box(160, 120, 20, 20, radius=10)), age=0.0)
    assert (cmd.vx, cmd.vz, cmd.yaw_rate) == pytest.approx((0, 0, 0))


def test_person_far_away_is_bounded():
    """The original's 20x20 px person asked for 8.6 m/s; ours stays at the bound then the limit."""
    cfg = colour_config(
        mode="follow_person",
        follow_person=FollowPersonConfig(
            area_ratio=20, max_forward_error=10, vx=PidGains(kp=0.05, out_limit=2.0)
        ),
    )
    servo = Servo(cfg)
    cmd = servo.step(0.0, frame(1.0, box(160, 120, 20, 20), detector="yolox"), age=0.0)
    assert cmd.errors is not None and cmd.errors.x == pytest.approx(10.0)
    assert cmd.vx == pytest.approx(0.5)


def test_same_frame_twice_repeats_the_command():
    servo = Servo(colour_config())
    msg = frame(1.0, box(100, 100, 10, 10, radius=8))
    first = servo.step(0.0, msg, age=0.0)
    again = servo.step(0.05, msg, age=0.05)
    assert again == first


def test_stale_detections_hover_and_never_search():
    servo = Servo(colour_config())
    servo.step(0.0, frame(1.0, box(100, 100, 10, 10, radius=8)), age=0.0)
    old = frame(1.0, box(100, 100, 10, 10, radius=8))
    for t in (0.6, 3.0, 30.0):
        cmd = servo.step(t, old, age=t)
        assert cmd.state == CONTROLLER_HOVER
        assert (cmd.vx, cmd.vz, cmd.yaw_rate) == (0, 0, 0)
    assert servo.step(1.0, None, age=float("inf")).state == CONTROLLER_HOVER


def test_lost_target_hovers_then_searches_towards_last_side():
    servo = Servo(colour_config(search_delay=2.0, search_yaw_rate=0.3))
    servo.step(0.0, frame(1.0, box(300, 120, 10, 10, radius=8)), age=0.0)  # last seen on the right
    cmd = servo.step(1.0, frame(2.0), age=0.0)  # fresh frame, no target
    assert cmd.state == CONTROLLER_HOVER and not cmd.target_visible
    assert (cmd.vx, cmd.vz, cmd.yaw_rate) == (0, 0, 0)
    cmd = servo.step(2.5, frame(3.5), age=0.0)
    assert cmd.state == CONTROLLER_SEARCH
    assert cmd.yaw_rate == pytest.approx(-0.3)  # clockwise: towards the right
    assert cmd.vx == 0 and cmd.vz == 0


def test_search_turns_left_when_last_seen_left_and_from_the_start():
    servo = Servo(colour_config())
    assert servo.step(0.0, frame(1.0), age=0.0).state == CONTROLLER_SEARCH  # never seen: search
    servo.step(1.0, frame(2.0, box(20, 120, 10, 10, radius=8)), age=0.0)
    assert servo.step(3.5, frame(4.5), age=0.0).yaw_rate == pytest.approx(0.3)


def test_reacquire_after_search_resets_pids():
    cfg = colour_config(yaw_rate=PidGains(kp=0.0, ki=1.0, out_limit=10.0))
    servo = Servo(cfg)
    for k in range(10):
        servo.step(k * 0.1, frame(k * 0.1, box(150, 120, 20, 20, radius=10)), age=0.0)
    assert servo.pid_yaw.integral > 0
    servo.step(5.0, frame(5.0), age=0.0)
    assert servo.pid_yaw.integral == 0.0
    cmd = servo.step(6.0, frame(6.0, box(150, 120, 20, 20, radius=10)), age=0.0)
    assert cmd.state == CONTROLLER_TRACKING and cmd.yaw_rate == 0.0  # no stale integral


def test_uses_tracker_target_not_the_best_detection():
    servo = Servo(colour_config(mode="follow_person"))
    msg = frame(
        1.0,
        box(40, 120, 60, 120, id_="7"),
        box(280, 120, 40, 90, id_="3"),
        target_id="3",
        detector="yolox",
    )
    assert pick_target(msg, best_when_untargeted=False).id == "3"
    cmd = servo.step(0.0, msg, age=0.0)
    assert cmd.target_id == "3" and cmd.yaw_rate < 0  # target is on the right


def test_target_id_not_in_frame_means_not_visible():
    msg = frame(1.0, box(40, 120, 60, 120, id_="7"), target_id="3", detector="yolox")
    assert pick_target(msg, best_when_untargeted=True) is None
    cmd = Servo(colour_config(mode="follow_person")).step(0.0, msg, age=0.0)
    assert not cmd.target_visible and cmd.state != CONTROLLER_TRACKING


def test_untracked_detections_use_the_best_first():
    msg = frame(1.0, box(40, 120, 20, 20, radius=9), box(280, 120, 10, 10, radius=5))
    assert pick_target(msg, best_when_untargeted=False).bbox.center.position.x == 40


def test_malformed_frame_size_is_not_a_target():
    msg = msgspec.structs.replace(frame(1.0, box(40, 120, 20, 20, radius=9)), image_width=0)
    cmd = Servo(colour_config()).step(0.0, msg, age=0.0)
    assert cmd.state != CONTROLLER_TRACKING and (cmd.vx, cmd.vz) == (0, 0)


def test_vx_derivative_uses_frame_stamps():
    """Equal error changes, frames 0.1 s vs 0.05 s apart: D doubles (dt from the stamps)."""
    gains = PidGains(kp=0.0, kd=1.0, d_tau=0.0, out_limit=100)

    def vx_after(dt: float) -> float:
        servo = Servo(colour_config(follow_color=FollowColorConfig(target_radius=10, vx=gains)))
        servo.step(0.0, frame(10.0, box(160, 120, 20, 20, radius=10)), age=0.0)
        return servo.step(0.0, frame(10.0 + dt, box(160, 120, 20, 20, radius=11)), age=0.0).vx

    assert vx_after(0.05) == pytest.approx(2 * vx_after(0.1))


def test_bad_mode_is_refused():
    with pytest.raises(ValueError, match="mode"):
        ServoConfig(mode="follow_dog")


def test_observing_during_takeoff_sets_the_search_side_without_commanding():
    servo = Servo(colour_config(search_delay=1.0))
    assert servo.observe(0.0, frame(1.0, box(300, 120, 10, 10, radius=8)), age=0.0)  # right
    assert servo.pid_yaw.output == 0.0 and servo.last.state == CONTROLLER_HOVER
    assert not servo.observe(0.5, frame(1.5), age=0.0)
    cmd = servo.step(0.6, frame(1.6), age=0.0)
    assert cmd.state == CONTROLLER_HOVER  # seen 0.6 s ago: hover first
    cmd = servo.step(1.2, frame(2.2), age=0.0)
    assert cmd.state == CONTROLLER_SEARCH and cmd.yaw_rate == pytest.approx(-0.3)


def test_tracked_detections_without_a_target_are_not_followed():
    """The tracker lost the target (occluded): do not jump to the passer-by it still sees."""
    msg = frame(1.0, box(40, 120, 60, 120, id_="7"), target_id="", detector="yolox")
    assert pick_target(msg, best_when_untargeted=False) is None
    cmd = Servo(colour_config(mode="follow_person")).step(0.0, msg, age=0.0)
    assert cmd.state != CONTROLLER_TRACKING and cmd.yaw_rate >= 0 and cmd.vx == 0


def test_colour_follows_the_largest_blob_when_the_tracker_names_none():
    """One beacon: a new track id without a named target is still the beacon (paper's rule)."""
    msg = frame(1.0, box(100, 120, 20, 20, radius=9, id_="t2"), box(250, 120, 8, 8, id_="t3"))
    assert pick_target(msg, best_when_untargeted=True).id == "t2"
    cmd = Servo(colour_config()).step(0.0, msg, age=0.0)
    assert cmd.state == CONTROLLER_TRACKING and cmd.yaw_rate > 0


def test_target_hidden_mid_image_waits_longer_before_searching():
    """Lost near the centre (someone walked in front): turning away would lose it for good."""
    servo = Servo(colour_config(search_delay=2.0, occlusion_delay=6.0, edge_margin=0.25))
    servo.step(0.0, frame(1.0, box(200, 120, 10, 10, radius=8)), age=0.0)  # 40 ref px right
    for t in (1.0, 3.0, 5.9):
        assert servo.step(t, frame(1.0 + t), age=0.0).state == CONTROLLER_HOVER
    cmd = servo.step(6.1, frame(7.1), age=0.0)
    assert cmd.state == CONTROLLER_SEARCH and cmd.yaw_rate < 0


def test_target_lost_at_the_border_searches_after_the_short_delay():
    servo = Servo(colour_config(search_delay=2.0, occlusion_delay=6.0, edge_margin=0.25))
    servo.step(0.0, frame(1.0, box(290, 120, 10, 10, radius=8)), age=0.0)  # 130 >= 120 ref px
    assert servo.step(2.1, frame(3.1), age=0.0).state == CONTROLLER_SEARCH


def test_a_new_target_id_must_persist_before_the_drone_turns_to_it():
    """The tracker names a passer-by for a frame: the drone does not swing towards them."""
    servo = Servo(colour_config(mode="follow_person", lost_hold=0.0))  # id_switch_confirm 0.5 s
    person = box(160, 120, 40, 96, id_="t1")
    passer = box(30, 120, 40, 96, id_="t8")
    assert servo.step(0.0, frame(1.0, person, target_id="t1"), age=0.0).target_id == "t1"
    cmd = servo.step(0.1, frame(1.1, person, passer, target_id="t8"), age=0.0)
    assert cmd.state == CONTROLLER_HOVER and cmd.yaw_rate == 0.0
    cmd = servo.step(0.2, frame(1.2, person, passer, target_id="t1"), age=0.0)
    assert cmd.state == CONTROLLER_TRACKING and cmd.target_id == "t1"  # back at once
    for t in (0.3, 0.6):
        cmd = servo.step(t, frame(1.0 + t, passer, target_id="t8"), age=0.0)
        assert cmd.state == CONTROLLER_HOVER
    cmd = servo.step(0.85, frame(1.85, passer, target_id="t8"), age=0.0)  # named 0.55 s
    assert cmd.state == CONTROLLER_TRACKING and cmd.target_id == "t8" and cmd.yaw_rate > 0


def test_colour_steers_on_a_new_blob_id_at_once():
    servo = Servo(colour_config())
    servo.step(0.0, frame(1.0, box(100, 120, 20, 20, radius=9, id_="t1"), target_id="t1"), 0.0)
    msg = frame(1.1, box(110, 120, 20, 20, radius=9, id_="t2"), target_id="t2")
    assert servo.step(0.1, msg, age=0.0).state == CONTROLLER_TRACKING


def test_a_dropout_shorter_than_lost_hold_keeps_the_command():
    servo = Servo(colour_config(lost_hold=0.3))
    first = servo.step(0.0, frame(1.0, box(60, 40, 10, 10, radius=5)), age=0.0)
    assert first.state == CONTROLLER_TRACKING and first.yaw_rate > 0
    held = servo.step(0.2, frame(1.2), age=0.0)  # one frame without the blob
    assert held == first
    assert servo.pid_yaw.output == first.yaw_rate  # PIDs not reset
    assert servo.step(0.35, frame(1.35), age=0.0).state == CONTROLLER_HOVER
    assert servo.step(0.4, None, age=float("inf")).state == CONTROLLER_HOVER


def test_stale_detections_never_hold_the_command():
    servo = Servo(colour_config(lost_hold=0.3))
    servo.step(0.0, frame(1.0, box(60, 40, 10, 10, radius=5)), age=0.0)
    assert servo.step(0.1, frame(1.0, box(60, 40, 10, 10, radius=5)), age=0.6).state == (
        CONTROLLER_HOVER
    )


def test_while_searching_a_newly_named_target_is_taken_at_once():
    servo = Servo(colour_config(mode="follow_person", search_delay=1.0))
    servo.step(0.0, frame(1.0, box(300, 120, 40, 96, id_="t1"), target_id="t1"), age=0.0)
    assert servo.step(1.5, frame(2.5), age=0.0).state == CONTROLLER_SEARCH
    cmd = servo.step(1.6, frame(2.6, box(250, 120, 40, 96, id_="t9"), target_id="t9"), age=0.0)
    assert cmd.state == CONTROLLER_TRACKING and cmd.target_id == "t9"
