"""The simulator's mission side (sim/dronewrapper_sim/px4/mission.py): PX4's answers to the
mission protocol, and its geofence action."""

from __future__ import annotations

import dataclasses
import math

from pymavlink.dialects.v20 import common as mavlink

from dronewrapper_sim.px4.autopilot import Autopilot, AutopilotConfig
from dronewrapper_sim.px4.geofence import Geofence
from dronewrapper_sim.px4.mission import FENCE, MISSION, MissionStore
from dronewrapper_sim.px4.modes import Mode

HOME = (47.397742, 8.545594)


def gcs(msg):
    """``msg`` as if it came from a ground station (system 255, component 190)."""
    msg._header = mavlink.MAVLink_header(msg.id, 0, 0, 255, 190)
    return msg


def item(seq: int, command: int = 16, frame: int = 3, mission_type: int = MISSION, **kw):
    fields = {"x": 473977420, "y": 85455940, "z": 5.0, "param1": 0.0}
    fields.update(kw)
    return gcs(
        mavlink.MAVLink_mission_item_int_message(
            1,
            1,
            seq,
            frame,
            command,
            0,
            1,
            fields["param1"],
            0,
            0,
            math.nan,
            fields["x"],
            fields["y"],
            fields["z"],
            mission_type,
        )
    )


def kinds(msgs) -> list[str]:
    return [m.get_type() for m in msgs]


def test_an_upload_is_asked_item_by_item_and_accepted():
    store = MissionStore(1)
    (req,) = store.handle(gcs(mavlink.MAVLink_mission_count_message(1, 1, 2, MISSION)), 0.0)
    assert (req.get_type(), req.seq) == ("MISSION_REQUEST_INT", 0)
    (req,) = store.handle(item(0), 0.1)
    assert req.seq == 1
    assert store.handle(item(0), 0.1) == []  # a duplicate: already taken
    (ack,) = store.handle(item(1), 0.2)
    assert (ack.get_type(), ack.type) == ("MISSION_ACK", mavlink.MAV_MISSION_ACCEPTED)
    assert len(store.mission) == 2 and store.version == 1


def test_an_item_ahead_of_the_expected_one_asks_again_for_the_missing_one():
    store = MissionStore(1)
    store.handle(gcs(mavlink.MAVLink_mission_count_message(1, 1, 3, MISSION)), 0.0)
    (req,) = store.handle(item(1), 0.1)
    assert req.seq == 0


def test_an_unsupported_command_or_frame_ends_the_upload_with_its_result():
    store = MissionStore(1)
    store.handle(gcs(mavlink.MAVLink_mission_count_message(1, 1, 2, MISSION)), 0.0)
    (ack,) = store.handle(item(0, command=183), 0.1)
    assert ack.type == mavlink.MAV_MISSION_UNSUPPORTED
    store.handle(gcs(mavlink.MAVLink_mission_count_message(1, 1, 1, MISSION)), 0.2)
    (ack,) = store.handle(item(0, frame=1), 0.3)  # MAV_FRAME_LOCAL_NED
    assert ack.type == mavlink.MAV_MISSION_UNSUPPORTED_FRAME
    assert store.mission == []


def test_a_stale_upload_is_dropped():
    store = MissionStore(1)
    store.handle(gcs(mavlink.MAVLink_mission_count_message(1, 1, 2, MISSION)), 0.0)
    assert store.handle(item(0), 6.0) == []  # past the 5 s upload timeout


def test_download_and_clear():
    store = MissionStore(1)
    store.handle(gcs(mavlink.MAVLink_mission_count_message(1, 1, 1, MISSION)), 0.0)
    store.handle(item(0), 0.1)
    (count,) = store.handle(gcs(mavlink.MAVLink_mission_request_list_message(1, 1, MISSION)), 1)
    assert count.count == 1
    (got,) = store.handle(gcs(mavlink.MAVLink_mission_request_int_message(1, 1, 0, MISSION)), 1)
    assert (got.get_type(), got.x, got.current) == ("MISSION_ITEM_INT", 473977420, 1)
    (bad,) = store.handle(gcs(mavlink.MAVLink_mission_request_int_message(1, 1, 4, MISSION)), 1)
    assert bad.type == mavlink.MAV_MISSION_INVALID_SEQUENCE
    (ack,) = store.handle(gcs(mavlink.MAVLink_mission_clear_all_message(1, 1, MISSION)), 2)
    assert ack.type == mavlink.MAV_MISSION_ACCEPTED and store.mission == []


def test_a_circle_fence_is_violated_outside_its_radius():
    store = MissionStore(1)
    store.handle(gcs(mavlink.MAVLink_mission_count_message(1, 1, 1, FENCE)), 0.0)
    store.handle(item(0, command=5003, frame=0, mission_type=FENCE, param1=20.0), 0.1)
    autopilot = Autopilot()
    fence = Geofence(store, autopilot.local_of)
    origin = autopilot.local_of(47.397742, 8.545594)
    assert not fence.violated(origin[0] + 19.0, origin[1])
    assert fence.violated(origin[0] + 21.0, origin[1])
    assert fence.breach(origin[0] + 21.0, origin[1])
    assert not fence.breach(origin[0] + 22.0, origin[1])  # once per excursion


def test_mission_mode_is_refused_in_the_air_without_a_mission():
    autopilot = Autopilot()
    cmd = autopilot.commander
    cmd.armed = True
    result = cmd.set_mode(Mode.MISSION, 1.0, autopilot.state)
    assert result == mavlink.MAV_RESULT_TEMPORARILY_REJECTED


def test_a_fence_breach_in_the_air_starts_gf_action_once():
    autopilot = Autopilot(AutopilotConfig(params={"GF_ACTION": 3}))  # 3: return
    store = autopilot.missions
    store.handle(gcs(mavlink.MAVLink_mission_count_message(1, 1, 1, FENCE)), 0.0)
    lat, lon = HOME
    fence = item(0, command=5003, frame=0, mission_type=FENCE, param1=20.0,
                 x=round(lat * 1e7), y=round(lon * 1e7))  # fmt: skip
    store.handle(fence, 0.1)
    cmd = autopilot.commander
    cmd.armed, cmd.landed = True, False
    inside = dataclasses.replace(autopilot.state, x=5.0, z=5.0)
    cmd.check_geofence(1.0, inside)
    assert cmd.nav_mode is Mode.LOITER
    outside = dataclasses.replace(autopilot.state, x=25.0, z=5.0)
    cmd.check_geofence(1.1, outside)
    assert cmd.nav_mode is Mode.RTL and cmd.user_mode is Mode.RTL
    assert any(t.text == "Geofence exceeded" for t in cmd.drain_texts())
    cmd.set_mode(Mode.LOITER, 1.2, outside)  # a pilot takes it back: no second action
    cmd.check_geofence(1.3, outside)
    assert cmd.nav_mode is Mode.LOITER


def test_a_lost_request_is_asked_again_on_the_uploads_link_until_the_item_comes():
    """PX4 re-sends a request after 0.25 s without its item, so a lost request (a full serial
    line) does not stall the upload; nothing is re-sent after the last item."""
    store = MissionStore(1)
    count = gcs(mavlink.MAVLink_mission_count_message(1, 1, 2, MISSION))
    assert [m.seq for m in store.handle(count, 0.0, "onboard")] == [0]
    assert store.retry(0.1, "onboard") == []  # not yet
    assert store.retry(0.3, "gcs") == []  # another link's upload is not this one
    (again,) = store.retry(0.3, "onboard")
    assert (again.get_type(), again.seq) == ("MISSION_REQUEST_INT", 0)
    assert store.retry(0.4, "onboard") == []  # 0.25 s after the last one
    assert [m.seq for m in store.handle(item(0), 0.5, "onboard")] == [1]
    assert store.retry(0.6, "onboard") == []
    assert [m.seq for m in store.retry(0.8, "onboard")] == [1]
    (ack,) = store.handle(item(1), 0.9, "onboard")
    assert ack.get_type() == "MISSION_ACK" and store.retry(5.0, "onboard") == []


def test_a_new_mission_starts_at_the_item_marked_current_else_the_last_current_one():
    # as PX4 02e73e3b6f: an upload that marks no item keeps the last mission's current item
    store = MissionStore(1)

    def upload(n: int, marked: int | None = None) -> None:
        store.handle(gcs(mavlink.MAVLink_mission_count_message(1, 1, n, MISSION)), 0.0)
        for seq in range(n):
            msg = item(seq)
            msg.current = int(seq == marked)
            store.handle(msg, 0.1)

    upload(3)
    store.set_current(2)
    upload(4)
    assert store.current == 2
    upload(2)
    assert store.current == 1  # within the new mission
    upload(4, marked=0)
    assert store.current == 0
