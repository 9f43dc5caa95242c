"""bridge_mavlink's envelope and missions (missions.py) on the pure core, over real MAVLink
bytes: refusals naming the limit, the breach action, uploads, downloads, the fence upload."""

from __future__ import annotations

import math

import pytest
from bridge_core_rig import OFFBOARD, CoreRig, ops, velocity
from pymavlink.dialects.v20 import common as mavlink
from targets import position

from dronewrapper.envelope import Envelope
from dronewrapper.msgs import registry
from dronewrapper.msgs.mavros import (
    MASK_POSITION,
    CommandTOL,
)
from dronewrapper.msgs.mission import (
    EnvelopeSet,
    MissionControl,
    Waypoint,
    WaypointClear,
    WaypointPull,
    WaypointPush,
)
from dronewrapper.runtime import ServiceError
from dronewrapper_bridge_mavlink import actions, missions, uploads

HOME_LAT, HOME_LON = 47.397742, 8.545594


def home(rig: CoreRig, east: float = 0.0, north: float = 0.0) -> None:
    """HOME_POSITION at local (east, north, 0) ENU."""
    rig.deliver(
        mavlink.MAVLink_home_position_message(
            round(HOME_LAT * 1e7),
            round(HOME_LON * 1e7),
            488000,
            north,
            east,
            0.0,
            [1.0, 0.0, 0.0, 0.0],
            0.0,
            0.0,
            0.0,
        )
    )


def flying(**config) -> CoreRig:
    config.setdefault("upload_fence", False)  # the tests of the fence turn it on
    rig = CoreRig(**config).connect(mode=OFFBOARD, armed=True, flying=True)
    rig.run(0.2)
    return rig


def texts(rig: CoreRig) -> list[str]:
    return [m.text for m in rig.published(registry.STATUSTEXT)]


def test_a_setpoint_above_the_envelope_is_refused_with_the_limit_named():
    rig = flying()
    start = rig.now
    rig.setpoint(position(0, 0, 500))
    assert rig.core.rejected_setpoints == 1
    assert not rig.setpoints(start, MASK_POSITION) or all(
        m.z > -400 for m in rig.setpoints(start, MASK_POSITION)
    )
    assert "bridge: setpoint refused: altitude 500 m above the envelope's 120 m" in texts(rig)


def test_a_setpoint_inside_is_forwarded():
    rig = flying()
    start = rig.now
    rig.setpoint(position(10, 0, 20))
    assert rig.core.rejected_setpoints == 0
    assert rig.setpoints(start, MASK_POSITION)[-1].z == pytest.approx(-20)


def test_the_envelope_is_measured_from_home():
    rig = flying(envelope=Envelope(max_distance=50))
    home(rig, east=40.0)
    rig.setpoint(position(85, 0, 5))  # 45 m from home
    assert rig.core.rejected_setpoints == 0
    rig.setpoint(position(-15, 0, 5))  # 55 m from home
    assert rig.core.rejected_setpoints == 1


def test_a_velocity_beyond_the_envelopes_speed_is_refused():
    rig = flying(envelope=Envelope(max_horizontal_speed=3))
    rig.setpoint(velocity(4.0))
    assert rig.core.rejected_setpoints == 1
    assert "horizontal speed 4 m/s above the envelope's 3 m/s" in texts(rig)[-1]


def test_a_takeoff_above_the_envelope_is_refused():
    rig = CoreRig().connect()
    op = rig.call(ops.takeoff, CommandTOL.takeoff(altitude=500.0))
    assert op.done
    with pytest.raises(ServiceError, match="take-off altitude 500 m above the envelope's 120 m"):
        op.result()
    assert not rig.commands(mavlink.MAV_CMD_NAV_TAKEOFF)


@pytest.mark.parametrize(
    ("action", "command"),
    [("return", mavlink.MAV_CMD_NAV_RETURN_TO_LAUNCH), ("land", mavlink.MAV_CMD_NAV_LAND)],
)
def test_a_breach_starts_the_envelopes_action_once(action, command):
    rig = flying(envelope=Envelope(max_altitude=10, breach_action=action, margin=1.0))
    rig.pose(down=-10.5)  # within the margin
    rig.run(0.2)
    assert not rig.commands(command)
    rig.pose(down=-12.0)  # blown above by the wind
    rig.run(1.2 if action == "return" else 0.1)  # a return first waits (1 s at most) for
    # the autopilot's return altitude
    assert len(rig.commands(command)) == 1
    assert any("envelope breach: altitude 12 m above the envelope's 10 m" in t for t in texts(rig))
    rig.ack(command, mavlink.MAV_RESULT_ACCEPTED)
    rig.run(1.0)
    assert len(rig.commands(command)) == 1


def test_a_breach_with_hold_asks_for_the_hold_mode():
    rig = flying(envelope=Envelope(max_distance=20, breach_action="hold", margin=0.0))
    rig.pose(north=25.0)
    rig.run(0.1)
    (sent,) = rig.commands(mavlink.MAV_CMD_DO_SET_MODE)
    assert (sent.param2, sent.param3) == (4, 3)  # AUTO.LOITER


def test_no_breach_on_the_ground():
    rig = CoreRig(envelope=Envelope(max_distance=1, margin=0.0)).connect()
    rig.pose(north=5.0, down=0.0)
    rig.run(0.2)
    assert not rig.commands(mavlink.MAV_CMD_NAV_RETURN_TO_LAUNCH)


def square(n: int = 4) -> list[Waypoint]:
    return [Waypoint(x_lat=HOME_LAT + 1e-4 * i, y_long=HOME_LON, z_alt=10.0) for i in range(n)]


def answer_upload(rig: CoreRig, mission_type: int = mavlink.MAV_MISSION_TYPE_MISSION) -> list:
    """Play the autopilot's side of an upload; returns the items received."""
    (count,) = rig.sent_since(-math.inf, "MISSION_COUNT")[-1:]
    received = []
    for seq in range(count.count):
        rig.deliver(mavlink.MAVLink_mission_request_int_message(255, 191, seq, mission_type))
        received.append(rig.sent_since(-math.inf, "MISSION_ITEM_INT")[-1])
    rig.deliver(mavlink.MAVLink_mission_ack_message(255, 191, 0, mission_type))
    return received


def test_mission_push_uploads_every_item_and_publishes_the_list():
    rig = flying()
    home(rig)
    op = rig.call(missions.push, WaypointPush(waypoints=square()))
    items = answer_upload(rig)
    rig.run(0.1)
    reply = op.result()
    assert reply.success and reply.wp_transfered == 4
    assert [i.x for i in items] == [round((HOME_LAT + 1e-4 * i) * 1e7) for i in range(4)]
    listing = rig.published(registry.MISSION_WAYPOINTS)[-1]
    assert len(listing.waypoints) == 4


def refused(rig: CoreRig, waypoints: list[Waypoint], match: str) -> None:
    """A push of ``waypoints`` is refused, its error matching ``match``."""
    op = rig.call(missions.push, WaypointPush(waypoints=waypoints))
    with pytest.raises(ServiceError, match=match):
        op.result()


def test_mission_push_refuses_an_item_outside_the_envelope():
    rig = flying()
    home(rig)
    far = [Waypoint(x_lat=HOME_LAT + 0.01, y_long=HOME_LON, z_alt=10.0)]  # 1.1 km north
    refused(rig, far, r"mission item 0: distance 1113\.19 m from home beyond")
    assert not rig.sent_since(-math.inf, "MISSION_COUNT")


def test_mission_push_refuses_an_item_above_the_ceiling():
    rig = flying()
    home(rig)
    high = [*square(2), Waypoint(x_lat=HOME_LAT, y_long=HOME_LON, z_alt=130.0)]
    refused(rig, high, r"mission item 2: altitude 130 m above the envelope's")
    takeoff = [Waypoint(command=mavlink.MAV_CMD_NAV_TAKEOFF, x_lat=0, y_long=0, z_alt=150.0)]
    refused(rig, takeoff, r"mission item 0: altitude 150 m above the envelope's")
    assert not rig.sent_since(-math.inf, "MISSION_COUNT")


def test_a_transfer_waits_for_the_running_one_to_end():
    rig = flying()
    home(rig)
    push = rig.call(missions.push, WaypointPush(waypoints=square(2)))
    pull = rig.call(missions.pull, WaypointPull())
    rig.run(0.2)
    assert rig.sent_since(-math.inf, "MISSION_REQUEST_LIST") == []  # the upload runs
    answer_upload(rig)
    assert push.result().success
    rig.run(0.2)
    assert len(rig.sent_since(-math.inf, "MISSION_REQUEST_LIST")) == 1  # now the download
    assert not pull.done


def test_mission_push_without_home_is_refused():
    rig = flying()
    op = rig.call(missions.push, WaypointPush(waypoints=square(1)))
    with pytest.raises(ServiceError, match="home is not known"):
        op.result()


def test_mission_push_partial_upload_is_reported():
    rig = flying()
    home(rig)
    op = rig.call(missions.push, WaypointPush(waypoints=square()))
    rig.deliver(mavlink.MAVLink_mission_request_int_message(255, 191, 0, 0))
    rig.deliver(mavlink.MAVLink_mission_request_int_message(255, 191, 1, 0))
    rig.deliver(mavlink.MAVLink_mission_ack_message(255, 191, mavlink.MAV_MISSION_NO_SPACE, 0))
    reply = op.result()
    assert not reply.success and reply.wp_transfered == 1
    assert "MAV_MISSION_NO_SPACE" in reply.message


def test_mission_pull_downloads_the_list():
    rig = flying()
    op = rig.call(missions.pull, WaypointPull())
    rig.deliver(mavlink.MAVLink_mission_count_message(255, 191, 1, 0))
    rig.deliver(
        mavlink.MAVLink_mission_item_int_message(
            255, 191, 0, 3, 16, 0, 1, 0, 0, 0, math.nan, 473977420, 85455940, 7.0, 0
        )
    )
    reply = op.result()
    assert reply.success and reply.waypoints[0].x_lat == pytest.approx(47.397742)
    assert rig.sent_since(-math.inf, "MISSION_ACK")


def test_mission_clear_and_progress():
    rig = flying()
    op = rig.call(missions.clear, WaypointClear())
    rig.deliver(mavlink.MAVLink_mission_ack_message(255, 191, 0, 0))
    assert op.result().success
    rig.deliver(mavlink.MAVLink_mission_current_message(3))  # PX4: the next item first
    rig.deliver(mavlink.MAVLink_mission_item_reached_message(2))
    rig.deliver(mavlink.MAVLink_mission_item_reached_message(2))  # PX4 repeats it
    rig.deliver(mavlink.MAVLink_mission_item_reached_message(3))
    assert [m.wp_seq for m in rig.published(registry.MISSION_REACHED)] == [2, 3]


def test_the_last_missions_reached_item_repeated_after_an_upload_is_not_this_missions():
    # PX4 SITL, 2026-11-28: after a 4-item mission, a new upload, then MISSION_ITEM_REACHED 3
    # again (its navigator's seq_reached outlives the upload): the new mission read finished,
    # and an unattended mission returned home before its first item
    rig = flying()
    rig.deliver(mavlink.MAVLink_mission_current_message(3))
    rig.deliver(mavlink.MAVLink_mission_item_reached_message(3))
    rig.core.missions.current_seq, rig.core.missions.last_reached = 0, -1  # as an upload does
    rig.deliver(mavlink.MAVLink_mission_item_reached_message(3))
    assert [m.wp_seq for m in rig.published(registry.MISSION_REACHED)] == [3]
    rig.deliver(mavlink.MAVLink_mission_item_reached_message(0))  # ArduPilot: reached first
    assert [m.wp_seq for m in rig.published(registry.MISSION_REACHED)] == [3, 0]


def test_mission_start_without_a_mission_is_refused():
    rig = flying()
    op = rig.call(actions.control, MissionControl(action="start"))
    with pytest.raises(ServiceError, match="no mission"):
        op.result()


def test_home_known_uploads_the_envelope_as_the_autopilots_fence():
    rig = flying(upload_fence=True)
    home(rig)
    (count,) = rig.sent_since(-math.inf, "MISSION_COUNT")
    assert count.mission_type == mavlink.MAV_MISSION_TYPE_FENCE and count.count == 1
    (circle,) = answer_upload(rig, mavlink.MAV_MISSION_TYPE_FENCE)
    assert circle.command == mavlink.MAV_CMD_NAV_FENCE_CIRCLE_INCLUSION
    assert circle.param1 == 500.0 + 1.0 + uploads.FENCE_BACKUP_M  # beyond the bridge's breach
    home(rig)  # again: no second upload
    assert len(rig.sent_since(-math.inf, "MISSION_COUNT")) == 1


def test_set_envelope_replaces_it_and_uploads_the_fence():
    rig = flying(upload_fence=True)
    home(rig)
    answer_upload(rig, mavlink.MAV_MISSION_TYPE_FENCE)  # the first, when home became known
    fence = [(-20.0, -20.0), (20.0, -20.0), (20.0, 20.0), (-20.0, 20.0)]
    op = rig.call(
        missions.set_envelope, EnvelopeSet(envelope=Envelope(max_altitude=30, fence=fence))
    )
    assert op.result().envelope.max_altitude == 30
    assert rig.published(registry.ENVELOPE)[-1].max_altitude == 30
    count = rig.sent_since(-math.inf, "MISSION_COUNT")[-1]
    assert count.mission_type == mavlink.MAV_MISSION_TYPE_FENCE and count.count == 5
    items = answer_upload(rig, mavlink.MAV_MISSION_TYPE_FENCE)
    assert items[0].command == mavlink.MAV_CMD_NAV_FENCE_CIRCLE_INCLUSION
    assert {i.command for i in items[1:]} == {mavlink.MAV_CMD_NAV_FENCE_POLYGON_VERTEX_INCLUSION}
    rig.setpoint(position(0, 0, 40))
    assert rig.core.rejected_setpoints == 1


def test_a_home_without_a_fix_or_with_a_non_finite_position_is_dropped():
    """Bad HOME_POSITIONs (no fix: latitude and longitude 0; NaN or infinite local position)
    set no home, start no fence upload and are counted; a good one sets home."""
    rig = CoreRig().connect()
    nan, inf = math.nan, math.inf

    def home(lat: int, lon: int, x: float, y: float, z: float):
        q = [1.0, 0.0, 0.0, 0.0]
        return mavlink.MAVLink_home_position_message(lat, lon, 488000, x, y, z, q, 0, 0, 0)

    for bad in (home(0, 0, 0.0, 0.0, 0.0), home(473977420, 85455940, nan, inf, nan)):
        since = rig.now
        rig.deliver(bad)
        rig.run(0.5)
        assert not rig.core.missions.home_known
        assert rig.sent_since(since, "MISSION_COUNT") == []
    rig.deliver(home(473977420, 85455940, 1.0, 2.0, -0.5))
    rig.run(0.5)
    assert rig.core.missions.home_known
    assert rig.core.missions.home_local == (2.0, 1.0, 0.5)


def test_a_mission_ending_in_a_camera_item_counts_as_ended_at_its_last_waypoint():
    # the unattended rule acts once the mission has ended; a QGroundControl survey's last item
    # (the camera trigger off) is never reported reached
    from dronewrapper_bridge_mavlink import watch

    rig = flying()
    rig.core.missions.waypoints = [
        Waypoint(command=command, x_lat=47.4, y_long=8.5, z_alt=5.0)
        for command in (16, 16, mavlink.MAV_CMD_DO_SET_CAM_TRIGG_DIST)
    ]
    rig.core.unattended.start("mission", "drone/alive/app", rig.core.now)
    rig.core.missions.last_reached = 0
    assert not watch.holding(rig.core)
    rig.core.missions.last_reached = 1
    assert watch.holding(rig.core)
