"""The station's wiring: its app served by uvicorn over real HTTP and WebSockets on loopback, its
Node on a real Zenoh router with a stand-in bridge (see station_env). What each route does is
tested on the fake bus (tests/service/test_station_routes.py); this proves the same routes
reach the real bus: discovery by liveliness, telemetry in, commands and setpoints out, video
frames through, the simulator's world query answered or said missing."""

from __future__ import annotations

import json
import time

import pytest
from station_env import POSE, TOKEN, StationEnv, station_env
from websockets.exceptions import InvalidStatus
from websockets.sync.client import connect

from dronewrapper.msgs import registry
from dronewrapper.msgs.mavros import MASK_POSITION, CommandBool
from dronewrapper.msgs.sensor import CompressedImage
from dronewrapper.msgs.std import Header
from support import client_node, wait_for

pytestmark = pytest.mark.timeout(120)

REMOTE = {"Host": "station.example:8080"}  # a page reached by a name that is not loopback


def _ws(env: StationEnv, path: str, **kw):
    return connect(f"ws://127.0.0.1:{env.port}{path}", open_timeout=10, **kw)


def _telemetry(ws) -> dict:
    while True:
        msg = json.loads(ws.recv(timeout=5))
        if msg["type"] == "telemetry":
            return msg


def _frame(k: int) -> CompressedImage:
    return CompressedImage(
        header=Header(stamp=1000.0 + k, frame_id="cam_frontal"), data=b"\xff\xd8" + bytes([k])
    )


def test_the_app_over_http_websockets_and_a_real_router(router) -> None:
    with station_env(router) as env, client_node(router, name="probe", mode="client") as probe:
        # HTTP: the page, the drone found by its bridge's token, its telemetry
        status, html, headers = env.http("GET", "/")
        assert status == 200 and '<canvas id="video"' in html
        assert "default-src 'self'" in headers["content-security-policy"]
        status, drones, _ = env.http("GET", "/api/drones")
        assert drones == [{"ns": "drone", "health": "ok", "services": ["bridge_test"]}]
        snap = env.http("GET", "/api/drones/drone")[1]
        assert (snap["pose"]["x"], snap["pose"]["y"], snap["pose"]["z"]) == POSE
        assert env.http("GET", "/api/objects")[1]["target"]["x"] == 5.0
        # a command reaches the bridge over Zenoh, and its refusal comes back with the reason
        assert env.http("POST", "/api/drones/drone/arm", {})[0] == 200
        assert env.bridge.requests[-1] == CommandBool(value=True)
        status, reply, _ = env.http("POST", "/api/drones/drone/disarm")
        assert status == 409 and reply["reason"] == "disarming denied in flight"
        # the access rule sees the real connection's Host
        assert env.http("POST", "/api/drones/drone/arm", {}, headers=REMOTE)[0] == 403
        with_token = {**REMOTE, "X-Station-Token": TOKEN}
        assert env.http("GET", "/api/session", headers=with_token)[1]["role"] == "operator"
        # no simulator on this bus: the world query says so
        world = env.http("GET", "/api/world")[1]
        assert world["simulator"] is False and "no simulator" in world["message"]

        # WebSockets: snapshots pushed, teleop out as setpoints, release holds
        setpoints = probe.latest(registry.SETPOINT_RAW_LOCAL)
        with _ws(env, "/ws/telemetry") as ws:
            first = _telemetry(ws)
            assert first["role"] == "operator" and first["drones"]["drone"]["pose"]["z"] == POSE[2]
            teleop = {"type": "teleop", "ns": "drone", "forward": 0.5, "left": 0, "up": 0}
            ws.send(json.dumps({**teleop, "turn": -1}))
            wait_for(
                lambda: (s := setpoints.fresh(0.5)) and s.type_mask != MASK_POSITION, 5, what="vel"
            )
            ws.send(json.dumps({"type": "teleop_release", "ns": "drone"}))
            sp = wait_for(
                lambda: (s := setpoints.fresh(0.5)) and s.type_mask == MASK_POSITION and s, 5
            )
            assert (sp.position.x, sp.position.y, sp.position.z) == POSE
        with pytest.raises(InvalidStatus), _ws(env, "/ws/telemetry", origin="http://evil.example"):
            pass

        # video: a frame published on the bus reaches the page
        pub = probe.publisher(registry.IMAGE_COMPRESSED, camera="cam_frontal")
        slot = env.fleet.get("drone").slots["frontal"]
        with _ws(env, "/ws/video/drone/frontal") as ws:
            k = 0
            while slot.value is None:  # until the station's new subscription hears one
                k += 1
                pub.put(_frame(k))
                time.sleep(0.02)
                assert k < 500, "no frame reached the station"
            data = ws.recv(timeout=5)
            n = int.from_bytes(data[:4], "big")
            header = json.loads(data[4 : 4 + n])
            assert header["ns"] == "drone" and header["camera"] == "frontal"
            assert data[4 + n : 4 + n + 2] == b"\xff\xd8"
