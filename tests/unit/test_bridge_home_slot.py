"""bridge_mavlink's mission numbering (home_slot.py): ArduPilot's item 0 is home, PX4 flies from
item 0; an upload marks its first item current; a stale PX4 report is not this mission's."""

from __future__ import annotations

import math

from bridge_core_rig import ARDUPILOT, CoreRig
from pymavlink.dialects.v20 import common as mavlink
from test_bridge_missions import HOME_LAT, HOME_LON, answer_upload, flying, home, square

from dronewrapper.msgs import registry
from dronewrapper.msgs.mission import WaypointPull, WaypointPush, WaypointSetCurrent
from dronewrapper_bridge_mavlink import missions

GUIDED = 4  # ArduCopter's custom mode


def ardupilot() -> CoreRig:
    rig = CoreRig(autopilot=ARDUPILOT, upload_fence=False)
    rig.connect(mode=GUIDED, armed=True, flying=True)
    rig.run(0.2)
    home(rig)
    return rig


def reached(rig: CoreRig) -> list[int]:
    return [m.wp_seq for m in rig.published(registry.MISSION_REACHED)]


def test_on_ardupilot_a_home_item_goes_first_and_its_numbers_are_shifted():
    rig = ardupilot()
    op = rig.call(missions.push, WaypointPush(waypoints=square(2)))
    items = answer_upload(rig)
    rig.run(0.1)
    assert op.result().success and op.result().wp_transfered == 2
    assert len(items) == 3 and items[0].command == mavlink.MAV_CMD_NAV_WAYPOINT
    assert (items[0].x, items[0].frame) == (round(HOME_LAT * 1e7), mavlink.MAV_FRAME_GLOBAL)
    assert [i.x for i in items[1:]] == [round((HOME_LAT + 1e-4 * i) * 1e7) for i in range(2)]
    assert items[1].current == 1  # flown from the first of ours
    assert len(rig.core.missions.waypoints) == 2
    rig.deliver(mavlink.MAVLink_mission_item_reached_message(0))  # its home: not ours
    rig.deliver(mavlink.MAVLink_mission_current_message(1))
    rig.deliver(mavlink.MAVLink_mission_item_reached_message(1))  # ArduPilot: reached first
    rig.deliver(mavlink.MAVLink_mission_item_reached_message(2))
    assert reached(rig) == [0, 1]
    assert rig.core.missions.current_seq == 0
    rig.call(missions.set_current, WaypointSetCurrent(wp_seq=1))
    (command,) = rig.sent_since(-math.inf, "COMMAND_LONG")[-1:]
    assert (command.command, command.param1) == (mavlink.MAV_CMD_DO_SET_MISSION_CURRENT, 2.0)


def test_on_ardupilot_a_download_drops_its_home_item():
    rig = ardupilot()
    op = rig.call(missions.pull, WaypointPull())
    rig.deliver(mavlink.MAVLink_mission_count_message(255, 191, 2, 0))
    for seq, lat in enumerate((HOME_LAT, HOME_LAT + 1e-4)):
        rig.deliver(
            mavlink.MAVLink_mission_item_int_message(
                255, 191, seq, 3, 16, 0, 1, 0, 0, 0, math.nan, round(lat * 1e7),
                round(HOME_LON * 1e7), 7.0, 0,
            )
        )  # fmt: skip
    reply = op.result()
    assert reply.wp_received == 1 and round(reply.waypoints[0].x_lat, 6) == 47.397842


def test_on_px4_the_first_item_is_marked_current_and_no_home_item_is_added():
    rig = flying()
    home(rig)
    rig.call(missions.push, WaypointPush(waypoints=square(3)))
    items = answer_upload(rig)
    assert len(items) == 3 and [i.current for i in items] == [1, 0, 0]


def test_on_ardupilot_a_start_already_in_auto_passes_through_guided_first():
    # a finished mission leaves ArduCopter in AUTO, where it starts a new one only on entering
    from dronewrapper.msgs.flight import MissionRequest
    from dronewrapper_bridge_mavlink import actions

    rig = ardupilot()
    rig.core.missions.waypoints = square(2)
    rig.custom_mode = 3  # AUTO
    rig.heartbeat()
    rig.run(0.1)
    rig.call(actions.mission_action, MissionRequest(action="start", timeout=10.0))
    rig.run(0.1)
    modes = [
        m.param2
        for _, m in rig.sent
        if m.get_type() == "COMMAND_LONG" and m.command == mavlink.MAV_CMD_DO_SET_MODE
    ]
    assert modes[:1] == [GUIDED], modes
