"""Missions, return-to-launch and the envelope flown end to end: bridge_mavlink's core against
the simulator's PX4-like autopilot (tests/sim_pair.py: real MAVLink bytes, virtual time),
judged from the simulator's ground truth.

Figures (printed with ``-s``): each waypoint's closest approach, the landing's distance from
home, and the fence reaction time (ground truth beyond the envelope's margin -> the autopilot
in AUTO.RTL).
"""

from __future__ import annotations

import math

import msgspec
import pytest
from sim_pair import SimPair
from targets import position

from dronewrapper.envelope import Envelope
from dronewrapper.geodesy import to_geodetic
from dronewrapper.msgs import registry
from dronewrapper.msgs.mavros import SetMode
from dronewrapper.msgs.mission import (
    MissionControl,
    Waypoint,
    WaypointPull,
    WaypointPush,
)
from dronewrapper.runtime import ServiceError
from dronewrapper_bridge_mavlink import actions, missions
from dronewrapper_bridge_mavlink import operations as ops

SQUARE = [(10.0, 0.0, 5.0), (10.0, 10.0, 5.0), (0.0, 10.0, 5.0), (0.0, 0.0, 5.0)]
FAST_RTL = {"RTL_RETURN_ALT": 6.0, "RTL_DESCEND_ALT": 3.0, "RTL_LAND_DELAY": 0.0}


def waypoints(pair: SimPair, points: list[tuple[float, float, float]]) -> list[Waypoint]:
    """Local ENU points as mission items (0.5 m acceptance, 0.5 s hold)."""
    home = pair.core.missions.home_geo
    items = []
    for x, y, z in points:
        lat, lon = to_geodetic(home, x, y)
        items.append(Waypoint(x_lat=lat, y_long=lon, z_alt=z, param1=0.5, param2=0.5))
    return items


def fly_square(pair: SimPair) -> float:
    """Upload and fly the square; the time it started."""
    pair.take_off(5.0)
    reply = pair.call(missions.push, WaypointPush(waypoints=waypoints(pair, SQUARE)))
    assert reply.success and reply.wp_transfered == 4, reply.message
    start = pair.t
    assert pair.call(actions.control, MissionControl(action="start")).success
    finished = pair.run(90.0, until=lambda: pair.autopilot.mode.name == "LOITER")
    assert finished, f"mission not finished: {pair.autopilot.mode.name} at {pair.position}"
    pair.run(0.5)
    return start


def test_a_four_waypoint_square_visits_each_waypoint_within_1_m():
    pair = SimPair()
    start = fly_square(pair)
    errors = [pair.closest_approach(point, start) for point in SQUARE]
    print(f"\nsquare: waypoint errors {', '.join(f'{e:.3f}' for e in errors)} m")
    assert max(errors) < 1.0
    assert [m.wp_seq for m in pair.published(registry.MISSION_REACHED, start)] == [0, 1, 2, 3]
    assert len(pair.published(registry.MISSION_WAYPOINTS)[-1].waypoints) == 4
    pulled = pair.call(missions.pull, WaypointPull())
    assert pulled.success and len(pulled.waypoints) == 4
    assert pulled.waypoints[1].x_lat == pytest.approx(waypoints(pair, SQUARE)[1].x_lat, abs=1e-7)


def test_the_upload_survives_lost_items():
    pair = SimPair()
    pair.take_off(3.0)
    lost = {"count": 0}

    def drop_two_items(msg) -> bool:
        if msg.get_type() == "MISSION_ITEM_INT" and msg.seq == 2 and lost["count"] < 2:
            lost["count"] += 1
            return True
        return False

    pair.drop_to_autopilot = drop_two_items
    reply = pair.call(missions.push, WaypointPush(waypoints=waypoints(pair, SQUARE)))
    assert reply.success and reply.wp_transfered == 4 and lost["count"] == 2


def test_an_item_the_autopilot_refuses_is_reported_with_the_partial_count():
    pair = SimPair()
    pair.take_off(3.0)
    items = waypoints(pair, SQUARE)
    items[2] = msgspec.structs.replace(items[2], command=183)  # DO_SET_SERVO
    reply = pair.call(missions.push, WaypointPush(waypoints=items))
    assert not reply.success and reply.wp_transfered == 2
    assert "MAV_MISSION_UNSUPPORTED" in reply.message


def test_return_to_launch_lands_within_1_m_of_home():
    pair = SimPair(params=FAST_RTL)
    pair.take_off(5.0)
    pair.call(missions.push, WaypointPush(waypoints=waypoints(pair, [(15.0, 8.0, 5.0)])))
    pair.call(actions.control, MissionControl(action="start"))
    assert pair.run(30.0, until=lambda: pair.autopilot.mode.name == "LOITER")
    assert math.hypot(pair.position[0] - 15.0, pair.position[1] - 8.0) < 1.0
    assert pair.call(actions.control, MissionControl(action="return")).success
    assert pair.run(90.0, until=lambda: not pair.autopilot.armed), "not landed and disarmed"
    error = math.hypot(pair.position[0], pair.position[1])
    print(f"\nRTL: landed {error:.3f} m from home")
    assert error < 1.0 and pair.position[2] < 0.1


def test_a_setpoint_beyond_the_fence_is_refused_and_never_flown():
    fence = [(-15.0, -15.0), (15.0, -15.0), (15.0, 15.0), (-15.0, 15.0)]
    pair = SimPair(envelope=Envelope(fence=fence))
    pair.take_off(4.0)
    pair.setpoint = position(0.0, 0.0, 4.0)
    pair.call(ops.set_mode, SetMode(custom_mode="OFFBOARD"))
    since = pair.t
    pair.setpoint = position(25.0, 0.0, 4.0)
    pair.run(5.0)
    assert pair.core.rejected_setpoints > 0
    texts = [m.text for m in pair.published(registry.STATUSTEXT, since)]
    assert any("position (25, 0) m outside the envelope's fence" in t for t in texts), texts
    assert max(p[0] for t, p, _ in pair.truth if t >= since) < 1.0  # it held where it was


def test_a_breach_by_the_wind_returns_the_aircraft_and_refuses_offboard_meanwhile():
    """A 12 m/s tailwind carries the aircraft past its target 0.5 m inside the envelope."""
    envelope = Envelope(max_distance=20.0, margin=1.0, breach_action="return")
    pair = SimPair(wind=(12.0, 0.0), envelope=envelope, params=FAST_RTL)
    pair.take_off(5.0)
    pair.setpoint = position(19.5, 0.0, 5.0)
    pair.call(ops.set_mode, SetMode(custom_mode="OFFBOARD"))
    assert pair.run(30.0, until=lambda: pair.autopilot.mode.name == "RTL"), "no breach action"
    crossed = next(t for t, p, _ in pair.truth if math.hypot(p[0], p[1]) > 21.0)
    in_rtl = pair.t  # the first step in AUTO.RTL
    print(f"\nfence: reaction time {in_rtl - crossed:.3f} s (margin crossed -> AUTO.RTL)")
    assert in_rtl - crossed < 0.5
    with pytest.raises(ServiceError, match="outside the envelope"):
        pair.call(ops.set_mode, SetMode(custom_mode="OFFBOARD"))
    assert pair.run(120.0, until=lambda: not pair.autopilot.armed), "not back and landed"
    landed = math.hypot(pair.position[0], pair.position[1])
    print(f"fence: landed {landed:.2f} m from home in the 12 m/s wind")
    assert landed < 5.0  # home, give or take the drift of a landing in a 12 m/s wind
