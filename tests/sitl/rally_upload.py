"""Rally points against real firmware, run by tests/sitl/test_rally_sitl.py inside a private
network namespace: once home is known, push a two-item mission with two rally points
(mission/push), then read the autopilot's rally list back (MISSION_REQUEST_LIST with
mission_type MAV_MISSION_TYPE_RALLY). Prints one JSON line; exits 0 when it ran to the end.

    python rally_upload.py px4 'udpin:127.0.0.1:14547'
    python rally_upload.py ardupilot 'tcp:127.0.0.1:5790'
"""

from __future__ import annotations

import json
import sys

from real_pair import RealPair

from dronewrapper.geodesy import to_geodetic
from dronewrapper.msgs.mission import NAV_RALLY_POINT, Waypoint, WaypointPush
from dronewrapper_bridge_mavlink import mission_transfer as mt
from dronewrapper_bridge_mavlink import missions, uploads

RALLY = [(30.0, 0.0, 5.0), (-20.0, 25.0, 8.0)]  # ENU m from home, m above home
MISSION = [(10.0, 0.0, 6.0), (10.0, 10.0, 6.0)]


def pull_rally(core, _request=None):
    """The autopilot's rally list (MAV_MISSION_TYPE_RALLY download)."""
    download = mt.Download(
        core.target(), core.now, mission_type=mt.RALLY, **uploads.transfer_args()
    )
    yield from uploads.run_transfer(core, download)
    return download


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
