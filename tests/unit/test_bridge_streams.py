"""The streams the bridge asks of the autopilot: the rates it publishes, the stops of what it
never reads, ATTITUDE stopped only while ATTITUDE_QUATERNION arrives (streams.py)."""

from __future__ import annotations

import pytest
from bridge_core_rig import CoreRig
from pymavlink.dialects.v20 import common as mavlink

from dronewrapper_bridge_mavlink.config import Config
from dronewrapper_bridge_mavlink.streams import QUATERNION_SILENCE_S, StreamRequests

INTERVAL = mavlink.MAV_CMD_SET_MESSAGE_INTERVAL
ATTITUDE = mavlink.MAVLINK_MSG_ID_ATTITUDE
UNUSED = {
    mavlink.MAVLINK_MSG_ID_ALTITUDE,
    mavlink.MAVLINK_MSG_ID_VFR_HUD,
    mavlink.MAVLINK_MSG_ID_POSITION_TARGET_LOCAL_NED,
}


def quaternion(rig: CoreRig) -> None:
    """An ATTITUDE_QUATERNION (level, heading north) stamped with the rig's time."""
    boot_ms = int(rig.now * 1000)
    rig.deliver(mavlink.MAVLink_attitude_quaternion_message(boot_ms, 1, 0, 0, 0, 0, 0, 0, [0] * 4))


def intervals(rig: CoreRig, since: float = float("-inf")) -> dict[int, list[float]]:
    """{message id: [interval µs asked, in order]} of the SET_MESSAGE_INTERVAL sent."""
    asked: dict[int, list[float]] = {}
    for m in rig.commands(INTERVAL, since):
        asked.setdefault(int(m.param1), []).append(m.param2)
    return asked


def test_unused_streams_are_stopped_and_attitude_kept_without_quaternions():
    rig = CoreRig(autopilot=mavlink.MAV_AUTOPILOT_ARDUPILOTMEGA).connect()
    rig.run(4.5)
    asked = intervals(rig)
    assert all(asked[msg_id] == [-1.0] * 3 for msg_id in UNUSED)  # 3 rounds, each a stop
    assert ATTITUDE not in asked  # no ATTITUDE_QUATERNION: ATTITUDE is the attitude


def test_attitude_is_stopped_while_quaternions_arrive_and_asked_back_when_they_stop():
    rig = CoreRig().connect()
    quaternion(rig)
    rig.run(0.5)
    assert intervals(rig)[ATTITUDE] == [-1.0]
    for _ in range(20):  # quaternions for 2 s: the next round stops ATTITUDE again
        quaternion(rig)
        rig.run(0.1)
    assert intervals(rig)[ATTITUDE] == [-1.0, -1.0]
    silent_from = rig.now
    rig.run(QUATERNION_SILENCE_S + 0.2)
    assert intervals(rig, silent_from)[ATTITUDE] == [0.0]  # its default rate, once
    rig.run(2.0)
    assert intervals(rig, silent_from)[ATTITUDE] == [0.0]  # not stopped again in silence
    pose = rig.core.telemetry
    rig.deliver(mavlink.MAVLink_attitude_message(int(rig.now * 1000), 0.0, 0.0, 1.0, 0, 0, 0))
    assert pose.attitude != (0.0, 0.0, 0.0, 1.0)  # ATTITUDE is read again


@pytest.mark.parametrize("connection", ["/dev/ttyTHS1", "udpin:127.0.0.1:14540"])
def test_a_serial_link_also_stops_what_pxs_onboard_mode_sends_unread(connection):
    """PX4 shares a serial port's data rate among all its streams: HIGHRES_IMU and ODOMETRY
    would crowd out the pose. Stopped on a serial link; a network link keeps them."""
    rig = CoreRig(connection=connection, baud=921600).connect()
    rig.run(0.5)
    asked = intervals(rig)
    serial = connection.startswith("/dev/")
    for name in ("HIGHRES_IMU", "ODOMETRY", "ATTITUDE_TARGET", "SERVO_OUTPUT_RAW"):
        msg_id = getattr(mavlink, f"MAVLINK_MSG_ID_{name}")
        assert (asked.get(msg_id) == [-1.0]) is serial, name
    assert all(asked[msg_id] == [-1.0] for msg_id in UNUSED)  # stopped on both
    with pytest.raises(ValueError, match="serial_unused_streams: 'NO_SUCH'"):
        Config(serial_unused_streams=["NO_SUCH"])


@pytest.mark.parametrize(
    "forwarding", [{"gcs_url": "udp:127.0.0.1:14550"}, {"gcs_over_zenoh": True}]
)
def test_nothing_is_stopped_while_forwarding_to_a_ground_station(forwarding):
    rig = CoreRig(**forwarding).connect()
    quaternion(rig)
    rig.run(4.5)
    assert all(interval > 0 for m in intervals(rig).values() for interval in m)
    assert len(intervals(rig)) == len(rig.core.config.message_rates)


def test_requests_in_one_round():
    streams = StreamRequests({"LOCAL_POSITION_NED": 50.0, "NO_SUCH": 5.0, "SYS_STATUS": 0.0},
                             ["VFR_HUD"], forwarding=False)  # fmt: skip
    lpn, vfr = mavlink.MAVLINK_MSG_ID_LOCAL_POSITION_NED, mavlink.MAVLINK_MSG_ID_VFR_HUD
    assert streams.round(0.0) == [(lpn, 20_000.0), (vfr, -1.0)]
    streams.on_quaternion(0.0)
    assert streams.round(0.5)[-1] == (ATTITUDE, -1.0) and streams.due(0.5) == []
    assert streams.due(0.5 + QUATERNION_SILENCE_S + 0.1) == [(ATTITUDE, 0.0)]


def test_unused_streams_must_name_messages():
    with pytest.raises(ValueError, match="NOT_A_MESSAGE"):
        Config(unused_streams=["NOT_A_MESSAGE"])
