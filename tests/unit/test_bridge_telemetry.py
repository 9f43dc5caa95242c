"""MAVLink telemetry (real MAVLink 2 bytes) -> MAVROS-equivalent messages."""

from __future__ import annotations

import math

from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from dronewrapper.msgs.mavros import LANDED_STATE_IN_AIR
from dronewrapper_bridge_mavlink import telemetry

_tx = mavlink2.MAVLink(None, srcSystem=1, srcComponent=1)


def wire(name: str, *args, **kwargs):
    """Encode with pymavlink, pack to bytes, parse back: the message as the bridge sees it."""
    msg = getattr(_tx, f"{name}_encode")(*args, **kwargs)
    return mavlink2.MAVLink(None).parse_char(msg.pack(_tx))


def test_px4_heartbeat_to_state():
    hb = wire("heartbeat", 2, 12, 29 | 128, 6 << 16, 4)
    state = telemetry.state_from_heartbeat(hb, 10.0)
    assert (state.mode, state.armed, state.guided, state.autopilot) == (
        "OFFBOARD", True, True, "px4",
    )  # fmt: skip
    assert state.connected and state.system_status == 4
    land = telemetry.state_from_heartbeat(wire("heartbeat", 2, 12, 29, (4 << 16) | (6 << 24), 3), 0)
    assert land.mode == "AUTO.LAND" and not land.armed and not land.guided


def test_ardupilot_heartbeat_to_state():
    state = telemetry.state_from_heartbeat(wire("heartbeat", 2, 3, 89 | 128, 4, 4), 0.0)
    assert (state.mode, state.guided, state.autopilot) == ("GUIDED", True, "ardupilotmega")


def test_gcs_heartbeats_are_not_the_autopilot():
    assert not telemetry.is_autopilot_heartbeat(wire("heartbeat", 6, 8, 0, 0, 4))
    assert telemetry.is_autopilot_heartbeat(wire("heartbeat", 2, 12, 0, 0, 3))


def test_local_position_and_attitude_to_enu_flu():
    tel = telemetry.Telemetry()
    # facing east (NED yaw +90 deg), level, flying north at 1 m/s, 3 m up
    tel.on_attitude(wire("attitude", 0, 0.0, 0.0, math.pi / 2, 0.0, 0.0, 0.2))
    pose, local, body = tel.on_local_position(
        wire("local_position_ned", 0, 5.0, 2.0, -3.0, 1.0, 0.0, -0.5), 12.5
    )
    p = pose.pose.position
    assert (p.x, p.y, p.z) == (2.0, 5.0, 3.0)
    assert pose.header.frame_id == "map" and pose.header.stamp == 12.5
    assert math.isclose(tel.yaw_enu, 0.0, abs_tol=1e-6)  # east in ENU
    assert (local.twist.linear.x, local.twist.linear.y) == (0.0, 1.0)
    assert math.isclose(local.twist.linear.z, 0.5)
    # north is to the LEFT of an east-facing vehicle: body FLU y = +1
    b = body.twist.linear
    assert math.isclose(b.y, 1.0, abs_tol=1e-6) and abs(b.x) < 1e-6
    assert math.isclose(b.z, 0.5, abs_tol=1e-6)
    assert math.isclose(body.twist.angular.z, -0.2, rel_tol=1e-6)  # CW (FRD) -> CCW negative
    assert body.header.frame_id == "base_link"


def test_attitude_quaternion_matches_attitude():
    a, b = telemetry.Telemetry(), telemetry.Telemetry()
    a.on_attitude(wire("attitude", 0, 0.1, -0.2, 0.7, 0, 0, 0))
    # q for rpy (0.1, -0.2, 0.7) in MAVLink (w, x, y, z) order
    from dronewrapper_bridge_base.frames import quat_from_rpy

    x, y, z, w = quat_from_rpy(0.1, -0.2, 0.7)
    b.on_attitude_quaternion(wire("attitude_quaternion", 0, w, x, y, z, 0, 0, 0))
    assert all(
        math.isclose(p, q, abs_tol=1e-6) for p, q in zip(a.attitude, b.attitude, strict=True)
    )


def test_global_position_needs_a_fix_and_gives_takeoff_amsl():
    tel = telemetry.Telemetry()
    assert tel.on_global_position(wire("global_position_int", 0, 0, 0, 0, 0, 0, 0, 0, 0), 1) is None
    tel.on_gps_raw(wire("gps_raw_int", 0, 1, 0, 0, 0, 0, 0, 0, 0, 0))  # no fix
    msg = wire("global_position_int", 0, 473977420, 85455940, 490000, 2000, 0, 0, 0, 0)
    assert tel.on_global_position(msg, 1.0) is None
    tel.on_gps_raw(wire("gps_raw_int", 0, 3, 0, 0, 0, 0, 0, 0, 0, 0))
    fix = tel.on_global_position(msg, 1.0)
    assert math.isclose(fix.latitude, 47.397742) and math.isclose(fix.longitude, 8.545594)
    assert math.isclose(fix.altitude, 490.0) and fix.status.status == 0
    assert math.isclose(tel.takeoff_altitude_amsl(5.0), 488.0 + 5.0)  # home = alt - relative


def test_extended_state():
    ext = telemetry.extended_state(wire("extended_sys_state", 0, LANDED_STATE_IN_AIR), 3.0)
    assert ext.landed_state == LANDED_STATE_IN_AIR and ext.header.stamp == 3.0


def test_battery_is_a_fraction():
    sys_status = wire("sys_status", 0, 0, 0, 500, 12100, 1530, 76, 0, 0, 0, 0, 0, 0)
    bat = telemetry.battery_from_sys_status(sys_status, 0.0)
    assert math.isclose(bat.percentage, 0.76) and math.isclose(bat.voltage, 12.1)
    assert math.isclose(bat.current, 15.3)
    no_battery = wire("sys_status", 0, 0, 0, 0, 65535, -1, -1, 0, 0, 0, 0, 0, 0)
    unknown = telemetry.battery_from_sys_status(no_battery, 0.0)
    assert math.isnan(unknown.percentage) and math.isnan(unknown.voltage)
    cells = [4000, 4000, 4100] + [65535] * 7
    bs = wire("battery_status", 0, 0, 0, 0, cells, -1, 0, 0, 55)
    bat2 = telemetry.battery_from_battery_status(bs, 0.0)
    assert math.isclose(bat2.percentage, 0.55) and math.isclose(bat2.voltage, 12.1)


def test_statustext_chunks_joined_and_tab_stripped():
    asm = telemetry.StatusTextAssembler()
    text = "Arming denied: Resolve system health failures first, then retry\t"
    first, rest = text[:50].encode(), text[50:].encode()
    assert asm.add(wire("statustext", 2, first, id=7, chunk_seq=0), 1.0, 0.0) == []
    done = asm.add(wire("statustext", 2, rest, id=7, chunk_seq=1), 1.0, 0.01)
    assert [t.text for t in done] == [text.rstrip()]
    assert done[0].severity == 2
    single = asm.add(wire("statustext", 6, b"Takeoff detected\t"), 2.0, 1.0)
    assert [t.text for t in single] == ["Takeoff detected"]


def test_statustext_lost_last_chunk_flushed_after_wait():
    asm = telemetry.StatusTextAssembler(max_wait=0.5)
    asm.add(wire("statustext", 4, b"x" * 50, id=3, chunk_seq=0), 1.0, 0.0)
    assert asm.flush(0.2) == []
    flushed = asm.flush(0.6, stamp=9.0)
    assert [t.text for t in flushed] == ["x" * 50]
