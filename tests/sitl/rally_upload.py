"""Rally points against real firmware, run by tests/sitl/test_missions_sitl.py inside a private
network namespace: once home is known, push a two-item mission with two rally points
(mission/push), then read the autopilot's rally list back (MISSION_REQUEST_LIST with
mission_type MAV_MISSION_TYPE_RALLY), and clear it with an empty list. Then upload
them again, fly the mission (its last item 8 m from the first rally point, 22 m from home),
return (mission/control ``return``) and report where it landed and how high it flew.

On ArduCopter the envelope's ceiling is 15 m (:data:`CEILING_M`) and its user had set
``RTL_CLIMB_MIN_M`` to 10 m (a return from the mission's 6 m would climb to 16 m): the bridge
keeps the return heights under the ceiling (autopilot_limits.py) and refuses a rally point at
14.5 m (a return there flies at the point's altitude: rally_returns.py). On PX4 the ceiling is
the default 120 m (its rule adds the return altitude to a rally point's: 5 m points and
its 30 m need more than 15 m). Prints one JSON line; exits 0 when it ran to the end.

    python rally_upload.py px4 'udpin:127.0.0.1:14547'
    python rally_upload.py ardupilot 'tcp:127.0.0.1:5790'
"""

from __future__ import annotations

import json
import math
import sys
import time

from real_pair import RealPair

from dronewrapper.envelope import Envelope
from dronewrapper.geodesy import to_geodetic
from dronewrapper.msgs.mavros import (
    CommandBool,
    CommandTOL,
    ParamGet,
    ParamSet,
    SetMode,
)
from dronewrapper.msgs.mission import (
    NAV_RALLY_POINT,
    EnvelopeSet,
    MissionControl,
    Waypoint,
    WaypointPush,
)
from dronewrapper.runtime import ServiceError
from dronewrapper_bridge_mavlink import actions, missions, parameters, uploads
from dronewrapper_bridge_mavlink import mission_transfer as mt
from dronewrapper_bridge_mavlink import operations as ops

RALLY = [(30.0, 0.0, 5.0), (-20.0, 25.0, 8.0)]  # ENU m from home, m above home
MISSION = [(10.0, 0.0, 6.0), (22.0, 0.0, 6.0)]
CEILING_M = {"ardupilot": 15.0, "px4": 120.0}
USER_CLIMB_MIN_M = 10.0  # ArduCopter RTL_CLIMB_MIN_M as its user left it


def pull_rally(core, _request=None):
    """The autopilot's rally list (MAV_MISSION_TYPE_RALLY download)."""
    return (yield from core.transfers.download(mt.RALLY))


def fly(pair: RealPair, kind: str, items: list, rally: list, report: dict) -> None:
    """Fly ``items`` and return with ``rally`` uploaded: where the return landed."""
    assert pair.call(missions.push, WaypointPush(waypoints=items, rally=rally)).success
    if kind == "ardupilot":
        pair.run(40.0)
        assert pair.call(ops.set_mode, SetMode(custom_mode="GUIDED")).mode_sent
    for _attempt in range(20):
        if pair.call(ops.arming, CommandBool(value=True)).success:
            break
        pair.run(2.0)
    pair.call(ops.takeoff, CommandTOL.takeoff(altitude=6.0))
    assert pair.run(40.0, until=lambda: pair.position[2] > 5.5), "no climb"
    pair.call(actions.control, MissionControl(action="start"))
    assert pair.run(90.0, until=lambda: len(items) - 1 in pair.reached), "mission not flown"
    report["rtl"] = pair.call(actions.control, MissionControl(action="return")).message
    start = time.monotonic()
    report["rtl_landed"] = pair.run(150.0, until=lambda: not pair.armed)
    x, y = pair.position[0], pair.position[1]
    report["landed_enu_from_home"] = (round(x, 2), round(y, 2))
    report["landed_from_rally_0_m"] = round(math.hypot(x - RALLY[0][0], y - RALLY[0][1]), 2)
    report["rtl_max_height_m"] = round(max(p[2] for t, p, _ in pair.track if t >= start), 2)
    report["texts"] = [t for t in pair.texts if "RTL" in t or "rally" in t.lower()][-6:]


def param(pair: RealPair, name: str) -> float | None:
    got = pair.call(parameters.param_get, ParamGet(param_id=name))
    return got.value.as_number() if got.success else None


def ardupilot_limits(pair: RealPair, report: dict, home) -> None:
    """The user's RTL_CLIMB_MIN_M, then the 15 m envelope: the return heights the bridge
    keeps, and a rally point at 14.5 m refused."""
    climb = ParamSet.of("RTL_CLIMB_MIN_M", USER_CLIMB_MIN_M)
    assert pair.call(parameters.param_set, climb).success, "RTL_CLIMB_MIN_M not set"
    envelope = Envelope(max_altitude=CEILING_M["ardupilot"])
    assert pair.call(missions.set_envelope, EnvelopeSet(envelope=envelope)).success
    key = (pair.core.autopilot, envelope)
    pair.run(20.0, until=lambda: pair.core.missions.limits.written_for == key)
    report["limits_problem"] = pair.core.missions.limits.problem
    names = ("RTL_ALT_M", "RTL_CLIMB_MIN_M", "RTL_ALT_FINAL_M", "RTL_ALT_TYPE")
    report["return_params"] = {name: param(pair, name) for name in names}
    lat, lon = to_geodetic(home, 30.0, 0.0)
    high = Waypoint(command=NAV_RALLY_POINT, x_lat=lat, y_long=lon, z_alt=14.5)
    try:
        pair.call(missions.push, WaypointPush(waypoints=[], rally=[high]))
        report["high_rally_refused"] = ""
    except ServiceError as exc:
        report["high_rally_refused"] = str(exc)


def main(kind: str, connection: str) -> int:
    report: dict = {"autopilot": kind}
    pair = RealPair(connection, upload_fence=False)
    try:
        ready = pair.run(
            90.0,
            until=lambda: pair.core.connected and pair.core.missions.home_geo is not None,
        )
        assert ready, "no heartbeat and home within 90 s"
        home = pair.core.missions.home_geo
        report["ceiling_m"] = CEILING_M[kind]
        if kind == "ardupilot":
            ardupilot_limits(pair, report, home)
        items = [
            Waypoint(x_lat=lat, y_long=lon, z_alt=z)
            for lat, lon, z in ((*to_geodetic(home, x, y), z) for x, y, z in MISSION)
        ]
        rally = [
            Waypoint(command=NAV_RALLY_POINT, x_lat=lat, y_long=lon, z_alt=z)
            for lat, lon, z in ((*to_geodetic(home, x, y), z) for x, y, z in RALLY)
        ]
        pushed = pair.call(missions.push, WaypointPush(waypoints=items, rally=rally))
        report["push"] = pushed.message
        assert pushed.success, pushed.message
        download = pair.call(pull_rally)
        report["pull_error"] = download.error
        report["rally_read_back"] = [
            (i.command, i.frame, i.x, i.y, round(i.z, 2)) for i in download.items
        ]
        sent = [uploads.item_of(wp) for wp in rally]
        report["same"] = [(i.x, i.y, round(i.z, 2)) for i in download.items] == [
            (i.x, i.y, round(i.z, 2)) for i in sent
        ]
        cleared = pair.call(missions.push, WaypointPush(waypoints=items, rally=[]))
        report["push_empty"] = cleared.message
        report["after_clear"] = len(pair.call(pull_rally).items)
        fly(pair, kind, items, rally, report)
        print(json.dumps(report))
        return 0 if report["same"] and report["after_clear"] == 0 else 1
    except AssertionError as exc:
        report["error"] = str(exc)
        print(json.dumps(report))
        return 1
    finally:
        pair.close()


if __name__ == "__main__":
    sys.exit(main(sys.argv[1], sys.argv[2]))
