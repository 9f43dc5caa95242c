"""Every endpoint of the station, over real HTTP and WebSockets on loopback, with a real Zenoh
router and a stand-in bridge (see station_env)."""

from __future__ import annotations

import json
import math
import socket
import time

import pytest
from station_env import POSE, TOKEN, StationEnv, assert_close, station_env
from websockets.exceptions import InvalidStatus
from websockets.sync.client import connect

from dronewrapper.msgs import registry
from dronewrapper.msgs.mavros import MASK_POSITION, CommandBool, SetMode, State
from dronewrapper.msgs.sensor import CompressedImage
from dronewrapper.msgs.simulation import WorldLoad, WorldState
from dronewrapper.msgs.std import Header
from dronewrapper.runtime import ServiceError
from support import client_node, wait_for

pytestmark = pytest.mark.timeout(120)

REMOTE = {"Host": "station.example:8080"}  # a page reached by a name that is not loopback


@pytest.fixture
def env(router):
    with station_env(router) as env:
        yield env


@pytest.fixture
def bus(router):
    with client_node(router, name="test_probe", mode="client") as node:
        yield node


def _setpoints(bus):
    return bus.latest(registry.SETPOINT_RAW_LOCAL)


def test_page_and_static_files(env: StationEnv) -> None:
    status, html, headers = env.http("GET", "/")
    assert status == 200 and '<canvas id="video"' in html
    assert "default-src 'self'" in headers["content-security-policy"]
    for name in ("app.js", "inputs.js", "plots.js", "style.css"):
        status, _, _ = env.http("GET", f"/static/{name}")
        assert status == 200, name
    assert env.http("GET", "/static/nope.js")[0] == 404


def test_session_says_the_role(env: StationEnv) -> None:
    status, info, _ = env.http("GET", "/api/session")
    assert status == 200 and info["role"] == "operator"
    assert info["limits"]["horizontal"] == env.config.teleop.horizontal
    assert info["token_required"] is True
    assert env.http("GET", "/api/session", headers=REMOTE)[1]["role"] == "observer"
    with_token = {**REMOTE, "X-Station-Token": TOKEN}
    assert env.http("GET", "/api/session", headers=with_token)[1]["role"] == "operator"


def test_drones_and_snapshot(env: StationEnv) -> None:
    status, drones, _ = env.http("GET", "/api/drones")
    assert status == 200
    assert drones == [{"ns": "drone", "health": "ok", "services": ["bridge_test"]}]
    status, snap, _ = env.http("GET", "/api/drones/drone")
    assert status == 200
    assert (snap["pose"]["x"], snap["pose"]["y"], snap["pose"]["z"]) == POSE
    assert snap["state"]["mode"] == "OFFBOARD" and snap["state"]["stale"] is False
    assert 0 <= snap["pose"]["age"] < 1.0
    assert snap["controller"] is None  # no controller on this bus
    assert env.http("GET", "/api/drones/ghost")[0] == 404


def test_arm_and_refusal_with_the_reason(env: StationEnv) -> None:
    status, reply, _ = env.http("POST", "/api/drones/drone/arm", {})
    assert status == 200 and reply["ok"] is True
    assert env.bridge.requests[-1] == CommandBool(value=True)
    status, reply, _ = env.http("POST", "/api/drones/drone/disarm")
    assert status == 409 and reply["reason"] == "disarming denied in flight"
    assert "disarming refused" in reply["error"]


def test_set_mode(env: StationEnv) -> None:
    assert env.http("POST", "/api/drones/drone/mode", {"mode": "AUTO.LOITER"})[0] == 200
    assert env.bridge.requests[-1] == SetMode(custom_mode="AUTO.LOITER")
    status, reply, _ = env.http("POST", "/api/drones/drone/mode", {"mode": "BOGUS"})
    assert status == 409 and "unknown mode BOGUS" in reply["error"]
    for bad in ({}, {"mode": 3}, {"mode": "a b;c"}):
        assert env.http("POST", "/api/drones/drone/mode", bad)[0] == 400, bad


@pytest.mark.parametrize(
    "body", [{}, {"height": "high"}, {"height": math.inf}, {"height": 0.1}, {"height": 31}]
)
def test_takeoff_validates_the_height(env: StationEnv, body) -> None:
    before = len(env.bridge.requests)
    status, reply, _ = env.http("POST", "/api/drones/drone/takeoff", body)
    assert status == 400 and "height" in reply["error"]
    assert len(env.bridge.requests) == before  # nothing was sent


def test_takeoff_while_flying_does_nothing(env: StationEnv) -> None:
    """Already flying: the SDK's take-off is idempotent and succeeds doing nothing."""
    status, reply, _ = env.http("POST", "/api/drones/drone/takeoff", {"height": 2.0})
    assert status == 200 and reply["ok"] is True


def test_bad_json_and_unknown_commands(env: StationEnv) -> None:
    assert env.http("POST", "/api/drones/drone/takeoff", b"{not json")[0] == 400
    assert env.http("POST", "/api/drones/drone/selfdestruct", {})[0] == 404
    assert env.http("POST", "/api/drones/ghost/arm", {})[0] == 404
    assert env.http("GET", "/api/drones/drone/arm")[0] == 405


def test_goto_and_hold_stream_position_setpoints(env: StationEnv, bus) -> None:
    setpoints = _setpoints(bus)
    assert env.http("POST", "/api/drones/drone/goto", {"x": 10.0, "y": -4.0})[0] == 200
    sp = wait_for(
        lambda: (s := setpoints.fresh(0.5)) and s.position.x == 10.0 and s, 5, what="goto"
    )
    assert sp.type_mask == MASK_POSITION
    assert (sp.position.y, sp.position.z) == (-4.0, POSE[2])  # at the current altitude
    assert env.http("POST", "/api/drones/drone/goto", {"x": 1e6, "y": 0})[0] == 400
    assert env.http("POST", "/api/drones/drone/hold", {})[0] == 200
    sp = wait_for(
        lambda: (s := setpoints.fresh(0.5)) and s.position.x == POSE[0] and s, 5, what="hold"
    )
    assert (sp.position.y, sp.position.z) == POSE[1:]


def test_land_waits_for_the_ground(env: StationEnv) -> None:
    status, reply, _ = env.http("POST", "/api/drones/drone/land", {})
    assert status == 200 and reply["ok"] is True, reply
    snap = wait_for(
        lambda: (
            (s := env.http("GET", "/api/drones/drone")[1])["landed"]["landed_state"] == "on_ground"
            and s
        ),
        5,
    )
    assert snap["state"]["armed"] is False


def test_observers_and_other_sites_cannot_command(env: StationEnv) -> None:
    status, reply, _ = env.http("POST", "/api/drones/drone/arm", {}, headers=REMOTE)
    assert status == 403 and "read-only" in reply["error"]
    bad_token = {**REMOTE, "X-Station-Token": "not-the-token-at-all"}
    assert env.http("POST", "/api/drones/drone/arm", {}, headers=bad_token)[0] == 403
    with_token = {**REMOTE, "X-Station-Token": TOKEN, "Origin": "http://station.example:8080"}
    assert env.http("POST", "/api/drones/drone/arm", {}, headers=with_token)[0] == 200
    evil = {"Origin": "http://evil.example"}
    status, reply, _ = env.http("POST", "/api/drones/drone/arm", {}, headers=evil)
    assert status == 403 and "cross-origin" in reply["error"]
    # observers still read
    assert env.http("GET", "/api/drones/drone", headers=REMOTE)[0] == 200


def test_objects_and_their_teleop(env: StationEnv, bus) -> None:
    status, objects, _ = env.http("GET", "/api/objects")
    assert status == 200 and objects["target"]["x"] == 5.0
    cmd = bus.latest(registry.SIM_OBJECT_CMD_VEL, name="target")
    path = "/api/objects/target/velocity"
    # the same command again until the probe's new subscription hears one (no fixed sleep)
    wait_for(
        lambda: env.http("POST", path, {"east": 1.0, "north": -0.5})[0] == 200 and cmd.value,
        10,
        what="the object's velocity command",
    )
    twist = cmd.value
    speed = env.config.object_speed
    assert (twist.linear.x, twist.linear.y) == (speed, -0.5 * speed)
    assert env.http("POST", path, {"east": 2.0, "north": 0})[0] == 400
    assert env.http("POST", "/api/objects/ghost/velocity", {"east": 0, "north": 0})[0] == 404
    assert env.http("POST", path, {"east": 0, "north": 0}, headers=REMOTE)[0] == 403


def test_world_of_the_simulator_is_shown_and_loaded(env: StationEnv, bus) -> None:
    status, reply, _ = env.http("GET", "/api/world")  # no simulator answers yet: said, no error
    assert status == 200 and reply["simulator"] is False and "no simulator" in reply["message"]
    loaded: list[str] = []

    def load(request: WorldLoad) -> WorldState:
        if request.scenario not in ("beacon_static", "empty"):
            raise ServiceError(f"unknown scenario {request.scenario!r}", "bad_request")
        loaded.append(request.scenario)
        return WorldState(scenario=request.scenario, objects=[], available=["beacon_static"])

    bus.serve(registry.SIM_WORLD, lambda _: WorldState(scenario="empty", available=["empty"]))
    bus.serve(registry.SIM_WORLD_LOAD, load)
    status, world = wait_for(
        lambda: (r := env.http("GET", "/api/world"))[0] == 200 and r[:2], 10, what="world"
    )
    assert world["simulator"] and world["scenario"] == "empty" and world["available"] == ["empty"]
    status, reply, _ = env.http("POST", "/api/world", {"scenario": "beacon_static"})
    assert status == 200 and reply["ok"] and reply["scenario"] == "beacon_static"
    status, reply, _ = env.http("POST", "/api/world", {"scenario": "../etc/passwd"})
    assert status == 400 and "unknown scenario" in reply["error"]
    assert env.http("POST", "/api/world", {})[0] == 400  # scenario is required
    assert env.http("POST", "/api/world", {"scenario": "empty"}, headers=REMOTE)[0] == 403
    assert loaded == ["beacon_static"]


# ---- WebSockets


def _ws(env: StationEnv, path: str, *, host: str = "", **kw):
    """A WebSocket to the station; ``host`` names it otherwise in the URL (and Host header)
    while the TCP connection still goes to loopback."""
    if not host:
        return connect(f"ws://127.0.0.1:{env.port}{path}", open_timeout=10, **kw)
    sock = socket.create_connection(("127.0.0.1", env.port), timeout=10)
    return connect(f"ws://{host}{path}", sock=sock, open_timeout=10, **kw)


def _telemetry(ws) -> dict:
    while True:
        msg = json.loads(ws.recv(timeout=5))
        if msg["type"] == "telemetry":
            return msg


def test_telemetry_socket_pushes_snapshots(env: StationEnv) -> None:
    with _ws(env, "/ws/telemetry") as ws:
        first, second = _telemetry(ws), _telemetry(ws)
    assert first["role"] == "operator"
    assert second["t"] > first["t"]
    drone = second["drones"]["drone"]
    assert drone["pose"]["z"] == POSE[2] and drone["pose"]["stale"] is False
    assert second["fleet"][0]["health"] == "ok"
    assert "target" in second["objects"]


def test_teleop_streams_velocity_and_release_holds(env: StationEnv, bus) -> None:
    setpoints = _setpoints(bus)
    limits = env.config.teleop
    with _ws(env, "/ws/telemetry") as ws:
        msg = {"type": "teleop", "ns": "drone", "forward": 0.5, "left": 0, "up": 0, "turn": -1}
        ws.send(json.dumps(msg))
        sp = wait_for(lambda: (s := setpoints.fresh(0.5)) and s.type_mask != MASK_POSITION and s, 5)
        assert_close(sp.velocity.x, 0.5 * limits.horizontal)
        assert_close(sp.yaw_rate, -limits.yaw_rate)
        assert env.fleet.get("drone").deadman.active
        ws.send(json.dumps({"type": "teleop_release", "ns": "drone"}))
        sp = wait_for(lambda: (s := setpoints.fresh(0.5)) and s.type_mask == MASK_POSITION and s, 5)
        assert (sp.position.x, sp.position.y, sp.position.z) == POSE
        assert not env.fleet.get("drone").deadman.active


def test_teleop_not_renewed_expires_into_a_hold(env: StationEnv, bus) -> None:
    setpoints = _setpoints(bus)
    link = env.fleet.get("drone")
    with _ws(env, "/ws/telemetry") as ws:
        msg = {"type": "teleop", "ns": "drone", "forward": 1, "left": 0, "up": 0, "turn": 0}
        ws.send(json.dumps(msg))
        wait_for(lambda: link.deadman.active, 5, what="teleop")
        started = time.monotonic()
        # the station's dead-man check runs in the process loop; here we run it by hand
        wait_for(lambda: link.check_deadman() or not link.deadman.active, 5, what="expiry")
        assert time.monotonic() - started >= env.config.teleop.timeout * 0.9
        sp = wait_for(lambda: (s := setpoints.fresh(0.5)) and s.type_mask == MASK_POSITION and s, 5)
        assert sp.position.z == POSE[2]


def test_closing_the_page_holds_the_drone(env: StationEnv, bus) -> None:
    setpoints = _setpoints(bus)
    link = env.fleet.get("drone")
    with _ws(env, "/ws/telemetry") as ws:
        msg = {"type": "teleop", "ns": "drone", "forward": 0, "left": 1, "up": 0, "turn": 0}
        ws.send(json.dumps(msg))
        wait_for(lambda: link.deadman.active, 5, what="teleop")
    wait_for(lambda: not link.deadman.active, 5, what="release on close")
    wait_for(lambda: (s := setpoints.fresh(0.5)) and s.type_mask == MASK_POSITION, 5)


def test_bad_and_forbidden_socket_messages_are_answered(env: StationEnv) -> None:
    def error_for(ws, msg) -> str:
        ws.send(msg if isinstance(msg, str | bytes) else json.dumps(msg))
        while True:
            reply = json.loads(ws.recv(timeout=5))
            if reply["type"] == "error":
                return reply["error"]

    with _ws(env, "/ws/telemetry") as ws:
        assert "forward" in error_for(ws, {"type": "teleop", "ns": "drone", "forward": 9})
        assert "unknown message type" in error_for(ws, {"type": "launch"})
        assert "no drone" in error_for(
            ws, {"type": "teleop", "ns": "ghost", "forward": 0, "left": 0, "up": 0, "turn": 0}
        )
        assert error_for(ws, "{not json")
        assert error_for(ws, b"\x00binary")  # answered; the socket stays open
        assert "unknown message type" in error_for(ws, {"type": "what"})
    assert not env.fleet.get("drone").deadman.active
    with _ws(env, "/ws/telemetry", host=REMOTE["Host"]) as ws:
        assert _telemetry(ws)["role"] == "observer"
        msg = {"type": "teleop", "ns": "drone", "forward": 1, "left": 0, "up": 0, "turn": 0}
        assert "read-only" in error_for(ws, msg)
    assert not env.fleet.get("drone").deadman.active


def test_cross_origin_sockets_are_refused(env: StationEnv) -> None:
    with pytest.raises(InvalidStatus), _ws(env, "/ws/telemetry", origin="http://evil.example"):
        pass


def _frame(k: int) -> CompressedImage:
    return CompressedImage(
        header=Header(stamp=1000.0 + k, frame_id="cam_frontal"), data=b"\xff\xd8" + bytes([k])
    )


def test_video_is_latest_only_one_frame_in_flight(env: StationEnv, bus) -> None:
    pub = bus.publisher(registry.IMAGE_COMPRESSED, camera="cam_frontal")
    slot = env.fleet.get("drone").slots["frontal"]
    with _ws(env, "/ws/video/drone/frontal") as ws:
        k = 0

        def publish_until(seq: int) -> None:
            nonlocal k
            while slot.latest() is None or slot.latest().seq < seq:
                k += 1
                pub.put(_frame(k))
                time.sleep(0.02)

        publish_until(1)
        data = ws.recv(timeout=5)
        n = int.from_bytes(data[:4], "big")
        header = json.loads(data[4 : 4 + n])
        assert header["ns"] == "drone" and header["camera"] == "frontal"
        assert data[4 + n : 4 + n + 2] == b"\xff\xd8"
        first = header["seq"]
        publish_until(first + 5)
        with pytest.raises(TimeoutError):
            ws.recv(timeout=0.3)  # nothing more until the page acknowledges
        ws.send("ack")
        data = ws.recv(timeout=5)
        n = int.from_bytes(data[:4], "big")
        newest = json.loads(data[4 : 4 + n])
        assert newest["seq"] >= first + 5  # skipped to the newest, no backlog
        assert newest["stamp"] == 1000.0 + data[-1]


def test_video_of_unknown_camera_or_drone_is_refused(env: StationEnv) -> None:
    for path in ("/ws/video/drone/thermal", "/ws/video/ghost/frontal"):
        with pytest.raises(Exception), _ws(env, path) as ws:  # noqa: B017
            ws.recv(timeout=5)


def test_several_drones_with_their_health(env: StationEnv, router) -> None:
    with client_node(router, name="bridge_two", namespace="drone2") as second:
        state = second.publisher(registry.STATE)
        second.announce()

        def listed() -> list:
            env.fleet.discover()
            state.put(State(connected=False, autopilot="px4"))
            return [d for d in env.http("GET", "/api/drones")[1] if d["ns"] == "drone2"]

        entry = wait_for(lambda: (d := listed()) and d[0]["health"] != "stale" and d, 10)
        assert entry[0]["health"] == "no_autopilot"  # a bridge whose autopilot is not linked
        assert entry[0]["services"] == ["bridge_two"]
    wait_for(
        lambda: (
            env.fleet.discover()
            or [d["health"] for d in env.http("GET", "/api/drones")[1]] == ["ok", "offline"]
        ),
        10,
        what="drone2 offline once its bridge left",
    )
