"""One mission flight against real firmware, run by tests/sitl/test_missions_sitl.py inside a
private network namespace (the autopilots' UDP/TCP ports are fixed): take off, upload and fly a
square, pull it back, return home, then fly at the envelope's fence until a breach. Prints one
JSON line of figures and findings; exits 0 when the flight ran to the end.

    python mission_flight.py px4 'udpin:127.0.0.1:14540'
    python mission_flight.py ardupilot 'tcp:127.0.0.1:5760'
"""

from __future__ import annotations

import json
import math
import sys
import time

import msgspec
from real_pair import RealPair

from dronewrapper.envelope import Envelope
from dronewrapper.geodesy import to_geodetic
from dronewrapper.msgs.geometry import Point
from dronewrapper.msgs.mavros import (
    FRAME_LOCAL_NED,
    MASK_POSITION,
    CommandBool,
    CommandTOL,
    PositionTarget,
    SetMode,
)
from dronewrapper.msgs.mission import (
    EnvelopeSet,
    MissionControl,
    Waypoint,
    WaypointPull,
    WaypointPush,
)
from dronewrapper_bridge_mavlink import actions, missions
from dronewrapper_bridge_mavlink import operations as ops

SQUARE = [(10.0, 0.0, 6.0), (10.0, 10.0, 6.0), (0.0, 10.0, 6.0), (0.0, 0.0, 6.0)]
"""The square (ENU m from home), each corner held 1 s within 0.5 m (ArduCopter holds whole
seconds only, and cuts corners it need not stop at)."""
GUIDED = {"px4": "OFFBOARD", "ardupilot": "GUIDED"}


def target(x: float, y: float, z: float) -> PositionTarget:
    return PositionTarget(
        coordinate_frame=FRAME_LOCAL_NED, type_mask=MASK_POSITION, position=Point(x=x, y=y, z=z)
    )


def highest(pair: RealPair, since: float) -> float:
    """The highest altitude above the local origin (ENU z, m) flown since ``since``."""
    return round(max(p[2] for t, p, _ in pair.track if t >= since), 2)


def main(kind: str, connection: str) -> int:
    report: dict = {"autopilot": kind}
    # a 15 m ceiling under the firmware's own return altitude (PX4 30 m, ArduCopter 15 m): the
    # bridge must keep the autopilot's returns under it
    envelope = Envelope(max_distance=25.0, max_altitude=15.0, margin=1.0, breach_action="return")
    pair = RealPair(connection, envelope=envelope)
    try:
        ready = pair.run(
            90.0,
            until=lambda: (
                pair.core.connected
                and pair.core.pose() is not None
                and pair.core.missions.home_geo is not None
            ),
        )
        assert ready, "no heartbeat, position and home within 90 s"
        if kind == "ardupilot":  # GUIDED needs a GPS fix, then the take-off in GUIDED
            pair.run(40.0)
            assert pair.call(ops.set_mode, SetMode(custom_mode="GUIDED")).mode_sent
        home = pair.core.missions.home_geo
        for _attempt in range(20):  # the autopilot refuses to arm until its checks pass
            if pair.call(ops.arming, CommandBool(value=True)).success:
                break
            pair.run(2.0)
        report["takeoff"] = pair.call(ops.takeoff, CommandTOL.takeoff(altitude=6.0)).message
        assert pair.run(40.0, until=lambda: pair.position[2] > 5.5), "no climb"
        pair.run(3.0)
        items = []
        for x, y, z in SQUARE:
            lat, lon = to_geodetic(home, x, y)
            items.append(Waypoint(x_lat=lat, y_long=lon, z_alt=z, param1=1.0, param2=0.5))
        # (ArduPilot's item 0 is home: the bridge puts one before these, home_slot.py)
        pushed = pair.call(missions.push, WaypointPush(waypoints=items))
        report["push"] = pushed.message
        assert pushed.success, pushed.message
        pulled = pair.call(missions.pull, WaypointPull())
        report["pull"] = f"{pulled.wp_received} item(s): {pulled.message}"
        start = time.monotonic()
        report["start"] = pair.call(actions.control, MissionControl(action="start")).message
        done = pair.run(120.0, until=lambda: len(items) - 1 in pair.reached)
        pair.run(1.0)
        report["mission_finished"] = done
        report["waypoint_errors_m"] = [round(pair.closest_approach(p, start), 3) for p in SQUARE]
        report["rtl"] = pair.call(actions.control, MissionControl(action="return")).message
        rtl_start = time.monotonic()
        landed = pair.run(120.0, until=lambda: not pair.armed)
        report["rtl_max_altitude_m"] = highest(pair, rtl_start)
        report["rtl_landed"] = landed
        hx, hy, _ = pair.core.missions.home_local  # the return lands at home, not at the origin
        report["rtl_landing_error_m"] = round(
            math.hypot(pair.position[0] - hx, pair.position[1] - hy), 3
        )
        # the envelope: a setpoint beyond it is refused; then, 20 m out, the envelope shrinks
        # to 10 m around the aircraft's home: a breach, and the return it starts
        if kind == "ardupilot":  # it stays in RTL after landing, where it does not arm
            assert pair.call(ops.set_mode, SetMode(custom_mode="GUIDED")).mode_sent
        for _attempt in range(20):
            if pair.call(ops.arming, CommandBool(value=True)).success:
                break
            pair.run(2.0)
        report["takeoff_2"] = pair.call(ops.takeoff, CommandTOL.takeoff(altitude=6.0)).message
        assert pair.run(40.0, until=lambda: pair.position[2] > 5.5), "no second climb"
        hx, hy, hz = pair.core.missions.home_local
        pair.setpoint = target(hx, hy, hz + 6.0)
        report["guided"] = pair.call(ops.set_mode, SetMode(custom_mode=GUIDED[kind])).message
        refused_before = pair.core.rejected_setpoints
        pair.setpoint = target(hx + 30.0, hy, hz + 6.0)
        pair.run(2.0)
        report["beyond_fence_refused"] = pair.core.rejected_setpoints > refused_before
        pair.setpoint = target(hx + 20.0, hy, hz + 6.0)
        assert pair.run(30.0, until=lambda: pair.position[0] > 19.0), "did not fly out 20 m"
        shrunk = msgspec.structs.replace(envelope, max_distance=10.0)
        pair.call(missions.set_envelope, EnvelopeSet(envelope=shrunk))
        changed = time.monotonic()
        report["breach_action"] = pair.run(20.0, until=lambda: pair.mode in ("AUTO.RTL", "RTL"))
        if report["breach_action"]:
            report["breach_to_return_s"] = round(time.monotonic() - changed, 3)
        report["max_distance_m"] = round(max(math.hypot(*p[:2]) for _, p, _ in pair.track), 2)
        pair.setpoint = None
        pair.run(90.0, until=lambda: not pair.armed)
        report["breach_max_altitude_m"] = highest(pair, changed)
        report["reached"] = pair.reached
        report["texts"] = pair.texts[-25:]
        print(json.dumps(report))
        return 0
    except AssertionError as exc:
        report["failed"] = str(exc)
        report["texts"] = pair.texts[-15:]
        report["track_tail"] = [
            (round(t, 1), [round(v, 2) for v in p], mode) for t, p, mode in pair.track[-150::30]
        ]
        report["home_local"] = pair.core.missions.home_local
        print(json.dumps(report))
        return 1
    finally:
        pair.close()


if __name__ == "__main__":
    sys.exit(main(sys.argv[1], sys.argv[2]))
