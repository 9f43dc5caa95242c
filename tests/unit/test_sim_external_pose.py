"""The world around an external autopilot: its truth decoded from real MAVLink bytes (built by
pymavlink as PX4 SIH and ArduCopter SITL send them), placed in the scenario's frame, mapped to
the wall clock, and the pose at each frame's capture time (interpolated or extrapolated, with
its age)."""

from __future__ import annotations

import math

import pytest
from pymavlink.dialects.v20 import ardupilotmega as mavlink

from dronewrapper.rotations import quat_from_rpy, rpy_from_quat
from dronewrapper_sim.config import SimConfig
from dronewrapper_sim.external.alignment import Alignment, LocalTruth
from dronewrapper_sim.external.links import default_link, interval_request, parse_link
from dronewrapper_sim.external.pose_buffer import AgeStats, ClockMap, PoseBuffer, TimedPose
from dronewrapper_sim.external.truth import decode
from dronewrapper_sim.external.world_runner import ExternalPose
from dronewrapper_sim.world.scenario import load_scenario

LAT0, LON0, ALT0 = 47.397742, 8.545594, 488.0
M_PER_DEG = math.radians(1.0) * 6371000.0


def wire(msg):
    """``msg`` packed into MAVLink 2 bytes and parsed back, as the link would see it."""
    sender = mavlink.MAVLink(None, srcSystem=1, srcComponent=1)
    parsed = mavlink.MAVLink(None).parse_buffer(msg.pack(sender))
    assert parsed and len(parsed) == 1
    return parsed[0]


def ned_quat(yaw_ned: float, roll: float = 0.0, pitch: float = 0.0) -> list[float]:
    x, y, z, w = quat_from_rpy(roll, pitch, yaw_ned)
    return [w, x, y, z]


def hil_state(t_s, north=0.0, east=0.0, up=0.0, yaw_ned=0.0, vel_ned=(0, 0, 0), yawspeed=0.0):
    return wire(
        mavlink.MAVLink_hil_state_quaternion_message(
            int(t_s * 1e6), ned_quat(yaw_ned), 0.0, 0.0, yawspeed,
            round((LAT0 + north / M_PER_DEG) * 1e7),
            round((LON0 + east / (M_PER_DEG * math.cos(math.radians(LAT0)))) * 1e7),
            round((ALT0 + up) * 1000),
            *(round(v * 100) for v in vel_ned), 0, 0, 0, 0, -981,
        )
    )  # fmt: skip


def sim_state(north=0.0, east=0.0, up=0.0, yaw_ned=0.0):
    lat = LAT0 + north / M_PER_DEG
    lon = LON0 + east / (M_PER_DEG * math.cos(math.radians(LAT0)))
    w, x, y, z = ned_quat(yaw_ned)
    return wire(
        mavlink.MAVLink_sim_state_message(
            w, x, y, z, 0.0, 0.0, yaw_ned, 0.0, 0.0, -9.81, 0.0, 0.0, 0.0,
            lat * 1e7, lon * 1e7, ALT0 + up, 0.0, 0.0, 1.0, 0.0, 0.0,
            round(lat * 1e7), round(lon * 1e7),
        )
    )  # fmt: skip


def test_px4_truth_decodes_units_and_frames():
    truth = decode(hil_state(12.5, up=2.0, vel_ned=(1.0, -0.5, -0.2), yaw_ned=0.3))
    assert truth.time_s == pytest.approx(12.5)
    assert truth.alt_m == pytest.approx(ALT0 + 2.0, abs=1e-3)
    assert truth.vel_ned == pytest.approx((1.0, -0.5, -0.2))
    w, x, y, z = truth.q_wxyz
    assert rpy_from_quat((x, y, z, w))[2] == pytest.approx(0.3, abs=1e-6)


def test_px4_sih_truth_without_a_time_reads_as_none():
    assert decode(hil_state(0.0)).time_s is None  # PX4 SIH leaves time_usec at 0


def test_ardupilot_truth_reads_the_integer_position_and_has_no_time():
    truth = decode(sim_state(north=3.0, east=-2.0, up=1.5))
    assert truth.time_s is None
    assert (truth.lat_deg - LAT0) * M_PER_DEG == pytest.approx(3.0, abs=0.02)
    assert truth.vel_ned == pytest.approx((1.0, 0.0, 0.0))


def test_other_and_non_finite_messages_are_not_truth():
    assert decode(wire(mavlink.MAVLink_heartbeat_message(2, 12, 0, 0, 0, 3))) is None
    bad = mavlink.MAVLink_sim_state_message(*([math.nan] * 21), 0, 0)
    assert decode(bad) is None


def test_alignment_puts_the_autopilot_start_at_the_scenario_start_facing_its_way():
    # PX4 starts facing north (NED yaw 0 = ENU yaw pi/2); the scenario starts at (1, 2) facing
    # east: the world is turned by -90 deg, so flying north in the autopilot is +x here.
    origin = decode(hil_state(1.0, yaw_ned=0.0))
    align = Alignment(origin, 1.0, 2.0, 0.0)
    assert align.rotation == pytest.approx(-math.pi / 2)
    start = align.local(origin)
    assert start.position == pytest.approx((1.0, 2.0, 0.0), abs=0.01)
    assert start.rpy[2] == pytest.approx(0.0, abs=1e-6)
    north = align.local(decode(hil_state(2.0, north=5.0, up=2.5, vel_ned=(1.0, 0.0, -0.5))))
    assert north.position == pytest.approx((6.0, 2.0, 2.5), abs=0.02)
    assert north.velocity == pytest.approx((1.0, 0.0, 0.5), abs=1e-6)
    # heading: facing east in the autopilot (NED yaw +90 deg) is facing -y here
    east = align.local(decode(hil_state(3.0, yaw_ned=math.pi / 2, yawspeed=0.5)))
    assert east.rpy[2] == pytest.approx(-math.pi / 2, abs=1e-6)
    assert east.yaw_rate == pytest.approx(-0.5)  # NED clockwise = ENU clockwise (negative)


def test_clock_map_takes_the_least_delayed_arrival():
    clock = ClockMap(window_s=2.0)
    # autopilot clock starts at 10 s; wall clock at 1000 s; arrivals delayed 1..30 ms
    delays = [0.005, 0.030, 0.001, 0.020, 0.012]
    walls = [clock.wall_time(10.0 + 0.04 * i, 1000.0 + 0.04 * i + d) for i, d in enumerate(delays)]
    assert walls[-1] == pytest.approx(1000.0 + 0.16 + 0.001)  # the smallest delay seen
    assert clock.wall_time(None, 1234.5) == 1234.5  # no autopilot time: the arrival
    assert clock.wall_time(10.16, 1000.3) == 1000.3  # a clock standing still: the arrival
    # the autopilot restarts (its clock begins again): the old offset is forgotten
    assert clock.wall_time(0.5, 1001.0) == pytest.approx(1001.0)


def local(x, yaw=0.0, vx=0.0, yaw_rate=0.0):
    return LocalTruth((x, 0.0, 2.0), (0.0, 0.0, yaw), (vx, 0.0, 0.0), yaw_rate)


def test_pose_between_samples_is_interpolated_past_them_extrapolated_then_held():
    buf = PoseBuffer(max_extrapolation_s=0.1)
    assert buf.at(5.0) is None
    buf.add(TimedPose(1.00, local(0.0, yaw=3.1, vx=1.0)))
    buf.add(TimedPose(1.04, local(0.04, yaw=-3.1, vx=1.0, yaw_rate=0.5)))
    assert not buf.add(TimedPose(1.02, local(9.0)))  # not newer: dropped
    mid = buf.at(1.02)
    assert mid.position[0] == pytest.approx(0.02)
    assert abs(mid.rpy[2]) == pytest.approx(math.pi, abs=1e-6)  # the short way round
    assert not mid.extrapolated and mid.age_s == pytest.approx(-0.02)
    ahead = buf.at(1.07)
    assert ahead.extrapolated and ahead.age_s == pytest.approx(0.03)
    assert ahead.position[0] == pytest.approx(0.07)
    assert ahead.rpy[2] == pytest.approx(-3.1 + 0.015)
    held = buf.at(2.0)  # too old to extrapolate: held 0.1 s past the newest, age grows
    assert held.position[0] == pytest.approx(0.14) and held.age_s == pytest.approx(0.96)


def test_age_stats_report_and_reset():
    stats = AgeStats()
    buf = PoseBuffer()
    buf.add(TimedPose(0.0, local(0.0)))
    buf.add(TimedPose(0.04, local(0.04)))
    for t in (0.02, 0.05, 0.06, 0.08):
        stats.add(buf.at(t))
    frames, mean, p95, worst, extrapolated = stats.report()
    assert p95 == pytest.approx(0.04)
    assert frames == 4 and worst == pytest.approx(0.04)
    assert mean == pytest.approx((-0.02 + 0.01 + 0.02 + 0.04) / 4)
    assert extrapolated == pytest.approx(0.75)
    assert stats.report()[0] == 0


def test_external_pose_publishes_truth_in_the_scenario_frame_and_frames_at_capture_time():
    pose = ExternalPose(load_scenario("beacon_smooth"))
    before = pose.frame_pose(50.0)  # nothing yet: the scenario's start
    assert before.position == (0.0, 0.0, 0.0) and before.stamp == 50.0
    first = pose.add(hil_state(3.0), arrival_s=100.0)
    assert first.position == pytest.approx((0.0, 0.0, 0.0), abs=1e-6)
    assert first.stamp == pytest.approx(100.0)
    second = pose.add(hil_state(3.04, north=0.04, vel_ned=(1.0, 0, 0)), arrival_s=100.05)
    assert second.stamp == pytest.approx(100.04)  # the autopilot's time, not the late arrival
    assert second.position[0] == pytest.approx(0.04, abs=0.012)  # +x; degE7 = 1.1 cm
    frame = pose.frame_pose(100.06)
    assert frame.stamp == 100.06 and frame.position[0] == pytest.approx(0.06, abs=0.012)
    frames, _mean, _p95, worst, extrapolated = pose.ages.report()
    assert frames == 1 and worst == pytest.approx(0.02) and extrapolated == 1.0
    # a time that stands still (a repeat): the sample is placed at its arrival
    repeat = pose.add(hil_state(3.04, north=0.04), arrival_s=100.07)
    assert repeat.stamp == 100.07


def test_the_scenario_clock_starts_when_the_vehicle_leaves_the_ground():
    pose = ExternalPose(load_scenario("beacon_smooth"))
    pose.add(hil_state(1.0), arrival_s=10.0)
    pose.add(hil_state(1.04, up=0.25), arrival_s=10.04)
    assert not pose.airborne  # still on (or just above) the ground: the world waits
    pose.add(hil_state(1.08, up=0.35), arrival_s=10.08)
    assert pose.airborne
    pose.add(hil_state(1.12, up=0.0), arrival_s=10.12)
    assert pose.airborne  # once started, the scenario runs on


def test_link_specs_and_the_rate_request():
    assert default_link("px4-sih") == "udp:127.0.0.1:19410"
    assert default_link("ardupilot") == "tcp:127.0.0.1:5762"
    assert parse_link("tcp:127.0.0.1:5772") == ("tcp", "127.0.0.1", 5772)
    for bad in ("udp:19410", "serial:/dev/x:1", "udp:h:port", "udp:h:70000"):
        with pytest.raises(ValueError):
            parse_link(bad)
    request = wire(interval_request("SIM_STATE", 50.0, 1))
    assert request.command == mavlink.MAV_CMD_SET_MESSAGE_INTERVAL
    assert (request.param1, request.param2, request.target_system) == (108, 20000, 1)


@pytest.mark.parametrize(
    ("sets", "bad_key"),
    [
        ({"autopilot": "gazebo"}, "autopilot"),
        ({"autopilot": "px4-sih", "aircraft": "tello"}, "autopilot"),
        ({"autopilot": "ardupilot", "autopilot_link": "tcp:5762"}, "autopilot_link"),
        ({"truth_rate_hz": 0.0}, "truth_rate_hz"),
        ({"max_extrapolation_s": -0.1}, "max_extrapolation_s"),
    ],
)
def test_config_refuses_bad_autopilot_settings(sets, bad_key):
    with pytest.raises(ValueError, match=bad_key):
        SimConfig(**sets)
