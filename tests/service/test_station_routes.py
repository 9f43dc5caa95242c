"""Every route of the station, on the fake bus in bus time (see station_rig): the drones listed
with health and services, telemetry snapshots, commands reaching the bridge with the right
requests, land waiting for the ground, the teleop dead-man, the world's objects and scenarios,
observers read-only. tests/integration/test_station_app.py proves the same app's wiring over a
real router, HTTP and WebSockets.

Size: one test per route of one app on one rig (station_rig), in the app's order.
"""

from __future__ import annotations

import json
import math
import threading
import time
from pathlib import Path

import pytest
from asgi_driver import WebSocketRefused
from station_rig import REMOTE, TARGET, TOKEN, StationRig, X

from dronewrapper.msgs import registry
from dronewrapper.msgs.flight import LandRequest
from dronewrapper.msgs.mavros import (
    MASK_POSITION,
    CommandBool,
    PositionTarget,
    SetMode,
    State,
    StatusText,
)
from dronewrapper.msgs.sensor import CompressedImage
from dronewrapper.msgs.simulation import WorldLoad, WorldState
from dronewrapper.msgs.std import Header
from dronewrapper.runtime import ServiceError
from dronewrapper.runtime.fake import FakeNode

pytestmark = pytest.mark.timeout(60)
STATIC = (
    Path(__file__).resolve().parents[2]
    / "services/ground_station/dronewrapper_ground_station"
    / "static"
)

POSE = (X, 0.0, 2.0)


@pytest.fixture
def rig():
    rig = StationRig()
    yield rig
    rig.close()


def _close(a: float, b: float) -> None:
    assert math.isclose(a, b, abs_tol=1e-6), f"{a} != {b}"


def test_page_and_static_files(rig: StationRig) -> None:
    status, html, headers = rig.http("GET", "/")
    assert status == 200 and '<canvas id="video"' in html
    assert "default-src 'self'" in headers["content-security-policy"]
    for name in ("app.js", "inputs.js", "plots.js", "style.css"):
        assert rig.http("GET", f"/static/{name}")[0] == 200, name
    assert rig.http("GET", "/static/nope.js")[0] == 404


def test_session_says_the_role(rig: StationRig) -> None:
    status, info, _ = rig.http("GET", "/api/session")
    assert status == 200 and info["role"] == "operator"
    assert info["limits"]["horizontal"] == rig.config.teleop.horizontal
    assert info["token_required"] is True
    assert rig.http("GET", "/api/session", headers=REMOTE)[1]["role"] == "observer"
    with_token = {**REMOTE, "X-Station-Token": TOKEN}
    assert rig.http("GET", "/api/session", headers=with_token)[1]["role"] == "operator"


def test_drones_and_snapshot(rig: StationRig) -> None:
    status, drones, _ = rig.http("GET", "/api/drones")
    assert status == 200
    assert drones == [{"ns": "drone", "health": "ok", "services": ["bridge_fake"]}]
    status, snap, _ = rig.http("GET", "/api/drones/drone")
    assert status == 200
    assert (snap["pose"]["x"], snap["pose"]["y"], snap["pose"]["z"]) == POSE
    assert snap["state"]["mode"] == "OFFBOARD" and snap["state"]["stale"] is False
    assert 0 <= snap["pose"]["age"] < 1.0
    assert snap["controller"] is None  # no controller on this bus
    assert rig.http("GET", "/api/drones/ghost")[0] == 404


def test_telemetry_that_stops_goes_stale(rig: StationRig) -> None:
    stale_s = rig.config.stale_after / registry.STATE.rate_hz
    rig.bus.clock.advance_to(rig.bus.clock() + max(stale_s, 1.0) + 0.1)  # nothing ticks
    assert rig.http("GET", "/api/drones")[1][0]["health"] == "stale"
    assert rig.http("GET", "/api/drones/drone")[1]["state"]["stale"] is True
    rig.run(0.1)
    assert rig.http("GET", "/api/drones")[1][0]["health"] == "ok"


def test_arm_and_refusal_with_the_reason(rig: StationRig) -> None:
    status, reply, _ = rig.http("POST", "/api/drones/drone/arm", {})
    assert status == 200 and reply["ok"] is True
    assert rig.pilot.requests[-1] == CommandBool(value=True)
    rig.pilot.refuse["arming"] = "disarming denied in flight"
    status, reply, _ = rig.http("POST", "/api/drones/drone/disarm")
    assert status == 409 and reply["reason"] == "disarming denied in flight"
    assert "disarming refused" in reply["error"]
    assert rig.pilot.requests[-1] == CommandBool(value=False)


def test_set_mode(rig: StationRig) -> None:
    assert rig.http("POST", "/api/drones/drone/mode", {"mode": "AUTO.LOITER"})[0] == 200
    assert rig.pilot.requests[-1] == SetMode(custom_mode="AUTO.LOITER")
    rig.pilot.refuse["set_mode"] = "unknown mode BOGUS"
    status, reply, _ = rig.http("POST", "/api/drones/drone/mode", {"mode": "BOGUS"})
    assert status == 409 and "unknown mode BOGUS" in reply["error"]
    before = len(rig.pilot.requests)
    for bad in ({}, {"mode": 3}, {"mode": "a b;c"}):
        assert rig.http("POST", "/api/drones/drone/mode", bad)[0] == 400, bad
    assert len(rig.pilot.requests) == before  # nothing was sent


@pytest.mark.parametrize(
    "body", [{}, {"height": "high"}, {"height": math.inf}, {"height": 0.1}, {"height": 31}]
)
def test_takeoff_validates_the_height(rig: StationRig, body) -> None:
    before = len(rig.pilot.requests)
    status, reply, _ = rig.http("POST", "/api/drones/drone/takeoff", body)
    assert status == 400 and "height" in reply["error"]
    assert len(rig.pilot.requests) == before  # nothing was sent


def test_takeoff_while_flying_does_nothing(rig: StationRig) -> None:
    """Already flying: the SDK's take-off is idempotent and succeeds doing nothing."""
    status, reply, _ = rig.http("POST", "/api/drones/drone/takeoff", {"height": 2.0})
    assert status == 200 and reply["ok"] is True
    assert rig.pilot.called("takeoff") == 0 and rig.pilot.called("arming") == 0


def test_takeoff_from_the_ground_returns_at_altitude() -> None:
    rig = StationRig(autopilot={"flying": False})
    try:
        status, reply, _ = rig.http("POST", "/api/drones/drone/takeoff", {"height": 3.0})
        assert status == 200 and reply["ok"] is True, reply
        snap = rig.http("GET", "/api/drones/drone")[1]
        assert snap["state"]["armed"] is True
        assert snap["pose"]["z"] == pytest.approx(3.0, abs=0.3)  # the SDK's climb tolerance
    finally:
        rig.close()


def test_bad_json_and_unknown_commands(rig: StationRig) -> None:
    assert rig.http("POST", "/api/drones/drone/takeoff", b"{not json")[0] == 400
    assert rig.http("POST", "/api/drones/drone/selfdestruct", {})[0] == 404
    assert rig.http("POST", "/api/drones/ghost/arm", {})[0] == 404
    assert rig.http("GET", "/api/drones/drone/arm")[0] == 405


def test_goto_and_hold_send_position_setpoints(rig: StationRig) -> None:
    assert rig.http("POST", "/api/drones/drone/goto", {"x": 10.0, "y": -4.0})[0] == 200
    sp = rig.setpoint()
    assert sp.type_mask == MASK_POSITION
    assert (sp.position.x, sp.position.y, sp.position.z) == (10.0, -4.0, POSE[2])  # altitude kept
    assert rig.http("POST", "/api/drones/drone/goto", {"x": 1e6, "y": 0})[0] == 400
    assert rig.setpoint().position.x == 10.0  # the refused goto sent nothing
    assert rig.http("POST", "/api/drones/drone/hold", {})[0] == 200
    sp = rig.setpoint()
    assert sp.type_mask == MASK_POSITION
    assert (sp.position.x, sp.position.y, sp.position.z) == POSE


def test_land_waits_for_the_ground(rig: StationRig) -> None:
    status, reply, _ = rig.http("POST", "/api/drones/drone/land", {})
    assert status == 200 and reply["ok"] is True, reply
    assert rig.pilot.called("flight_land") == 1
    assert isinstance(rig.pilot.requests[-1], LandRequest)
    snap = rig.http("GET", "/api/drones/drone")[1]  # answered once on the ground
    assert snap["landed"]["landed_state"] == "on_ground"
    assert snap["state"]["armed"] is False


def test_land_refused_says_why(rig: StationRig) -> None:
    rig.pilot.refuse["flight_land"] = "landing denied"
    status, reply, _ = rig.http("POST", "/api/drones/drone/land", {})
    assert status == 409 and "landing denied" in reply["error"]


def test_observers_and_other_sites_cannot_command(rig: StationRig) -> None:
    status, reply, _ = rig.http("POST", "/api/drones/drone/arm", {}, headers=REMOTE)
    assert status == 403 and "read-only" in reply["error"]
    bad_token = {**REMOTE, "X-Station-Token": "not-the-token-at-all"}
    assert rig.http("POST", "/api/drones/drone/arm", {}, headers=bad_token)[0] == 403
    evil = {"Origin": "http://evil.example"}
    status, reply, _ = rig.http("POST", "/api/drones/drone/arm", {}, headers=evil)
    assert status == 403 and "cross-origin" in reply["error"]
    assert rig.pilot.called("arming") == 0  # none of them reached the bridge
    with_token = {**REMOTE, "X-Station-Token": TOKEN, "Origin": "http://station.example:8080"}
    assert rig.http("POST", "/api/drones/drone/arm", {}, headers=with_token)[0] == 200
    assert rig.pilot.called("arming") == 1
    assert rig.http("GET", "/api/drones/drone", headers=REMOTE)[0] == 200  # observers read


def test_objects_and_their_teleop(rig: StationRig) -> None:
    status, objects, _ = rig.http("GET", "/api/objects")
    assert status == 200 and objects["target"]["x"] == TARGET[0]
    cmd = rig.world.node.latest(registry.SIM_OBJECT_CMD_VEL, name="target")
    path = "/api/objects/target/velocity"
    assert rig.http("POST", path, {"east": 1.0, "north": -0.5})[0] == 200
    speed = rig.config.object_speed
    assert (cmd.value.linear.x, cmd.value.linear.y) == (speed, -0.5 * speed)
    assert cmd.count == 1
    assert rig.http("POST", path, {"east": 2.0, "north": 0})[0] == 400
    assert rig.http("POST", "/api/objects/ghost/velocity", {"east": 0, "north": 0})[0] == 404
    assert rig.http("POST", path, {"east": 0, "north": 0}, headers=REMOTE)[0] == 403
    assert cmd.count == 1  # the refused ones sent nothing


def test_objects_not_seen_for_5_s_are_dropped(rig: StationRig) -> None:
    rig.bus.clock.advance_to(rig.bus.clock() + 5.1)  # the simulator stopped
    assert rig.http("GET", "/api/objects")[1] == {}


def test_world_of_the_simulator_is_shown_and_loaded(rig: StationRig) -> None:
    status, reply, _ = rig.http("GET", "/api/world")  # no simulator answers yet: said, no error
    assert status == 200 and reply["simulator"] is False and "no simulator" in reply["message"]
    assert rig.http("POST", "/api/world", {"scenario": "empty"})[0] == 503
    loaded: list[str] = []

    def load(request: WorldLoad) -> WorldState:
        if request.scenario not in ("beacon_static", "empty"):
            raise ServiceError(f"unknown scenario {request.scenario!r}", "bad_request")
        loaded.append(request.scenario)
        return WorldState(scenario=request.scenario, objects=[], available=["beacon_static"])

    sim = rig.world.node
    sim.serve(registry.SIM_WORLD, lambda _: WorldState(scenario="empty", available=["empty"]))
    sim.serve(registry.SIM_WORLD_LOAD, load)
    status, world, _ = rig.http("GET", "/api/world")
    assert status == 200
    assert world["simulator"] and world["scenario"] == "empty" and world["available"] == ["empty"]
    status, reply, _ = rig.http("POST", "/api/world", {"scenario": "beacon_static"})
    assert status == 200 and reply["ok"] and reply["scenario"] == "beacon_static"
    status, reply, _ = rig.http("POST", "/api/world", {"scenario": "../etc/passwd"})
    assert status == 400 and "unknown scenario" in reply["error"]
    assert rig.http("POST", "/api/world", {})[0] == 400  # scenario is required
    assert rig.http("POST", "/api/world", {"scenario": "empty"}, headers=REMOTE)[0] == 403
    assert loaded == ["beacon_static"]


def test_several_drones_with_their_health(rig: StationRig) -> None:
    second = FakeNode("bridge_two", rig.bus, ns="drone2")
    second.announce()
    rig.fleet.discover()  # found by its token; then its State arrives
    second.publisher(registry.STATE).put(State(connected=False, autopilot="px4"))
    entry = [d for d in rig.http("GET", "/api/drones")[1] if d["ns"] == "drone2"]
    assert entry == [{"ns": "drone2", "health": "no_autopilot", "services": ["bridge_two"]}]
    # its commands go to its own namespace, not the first drone's
    status, reply, _ = rig.http("POST", "/api/drones/drone2/arm", {})
    assert status == 504 and "drone2/mavros/cmd/arming" in reply["error"]  # it serves nothing
    assert rig.pilot.called("arming") == 0
    second.close()
    rig.fleet.discover()
    assert [d["health"] for d in rig.http("GET", "/api/drones")[1]] == ["ok", "offline"]


def test_configured_namespaces_are_not_discovered() -> None:
    rig = StationRig(namespaces=["drone7"])
    try:
        assert [d["ns"] for d in rig.http("GET", "/api/drones")[1]] == ["drone7"]
        assert rig.http("GET", "/api/drones")[1][0]["health"] == "offline"
    finally:
        rig.close()


# ---- WebSockets


def _telemetry(ws) -> dict:
    while True:
        msg = json.loads(ws.recv(timeout=5))
        if msg["type"] == "telemetry":
            return msg


def _teleop(**sticks: float) -> str:
    return json.dumps({"type": "teleop", "ns": "drone", **sticks})


def _sent(rig: StationRig, velocity: bool, what: str) -> PositionTarget:
    """The newest setpoint once it is a velocity (or a position) one: the page's messages are
    handled on the app's thread."""

    def newest() -> PositionTarget | None:
        setpoints = rig.pilot.setpoints()
        sp = setpoints[-1][1] if setpoints else None
        return sp if sp is not None and (sp.type_mask != MASK_POSITION) == velocity else None

    arrived = threading.Event()  # set by the publication itself (the fake bus delivers at once)
    sub = rig.bus.subscribe(
        registry.SETPOINT_RAW_LOCAL.key("drone"),
        lambda _key, _payload, *_: newest() is not None and arrived.set(),
    )
    try:
        if newest() is None:
            assert arrived.wait(5), f"timed out waiting for {what}"
        return newest()
    finally:
        sub.undeclare()


def test_telemetry_socket_pushes_snapshots(rig: StationRig) -> None:
    with rig.websocket("/ws/telemetry") as ws:
        first, second = _telemetry(ws), _telemetry(ws)
    assert first["role"] == "operator"
    assert first["t"] == second["t"] == rig.bus.clock.time()  # the node's clock: bus time
    drone = second["drones"]["drone"]
    assert drone["pose"]["z"] == POSE[2] and drone["pose"]["stale"] is False
    assert second["fleet"][0]["health"] == "ok"
    assert "target" in second["objects"]


def test_the_page_is_told_when_the_stations_router_is_unreachable() -> None:
    """A green badge beside "no drone online" hid a lost router: the snapshot says it."""
    rig = StationRig()
    try:
        with rig.websocket("/ws/telemetry") as ws:
            assert _telemetry(ws)["router"]["linked"] is True
            rig.bus.link_gap(True)  # the station's node loses its router
            rig.fleet.discover()
            router = _telemetry(ws)["router"]
        assert router["linked"] is False and router["endpoint"]
    finally:
        rig.close()
    app_js = (STATIC / "app.js").read_text()
    assert "router unreachable" in app_js and "renderLink(msg.router)" in app_js


def test_the_log_shows_each_events_own_stamp(rig: StationRig) -> None:
    """The autopilot's text is logged at its stamp (local HH:MM:SS), not when it was received."""
    stamp = 1_700_000_000.0
    publisher = rig.pilot.node.publisher(registry.STATUSTEXT, key=registry.STATUSTEXT.key("drone"))
    publisher.put(StatusText(header=Header(stamp=stamp), severity=6, text="Takeoff detected"))
    rig.run(0.2)
    (entry,) = [e for e in rig.link.snapshot()["log"] if e["text"] == "Takeoff detected"]
    assert entry["stamp"] == stamp
    assert entry["time"] == time.strftime("%H:%M:%S", time.localtime(stamp))
    assert "e.severity, e.time)" in (STATIC / "app.js").read_text()  # the page shows it


def test_teleop_streams_velocity_and_release_holds(rig: StationRig) -> None:
    limits = rig.config.teleop
    link = rig.link
    with rig.websocket("/ws/telemetry") as ws:
        ws.send(_teleop(forward=0.5, left=0, up=0, turn=-1))
        sp = _sent(rig, velocity=True, what="velocity setpoints")
        _close(sp.velocity.x, 0.5 * limits.horizontal)
        _close(sp.yaw_rate, -limits.yaw_rate)
        assert link.deadman.active
        ws.send(json.dumps({"type": "teleop_release", "ns": "drone"}))
        sp = _sent(rig, velocity=False, what="a hold on release")
        assert (sp.position.x, sp.position.y, sp.position.z) == POSE
        assert not link.deadman.active


def test_teleop_not_renewed_expires_into_a_hold(rig: StationRig) -> None:
    link = rig.link
    timeout = rig.config.teleop.timeout
    with rig.websocket("/ws/telemetry") as ws:
        ws.send(_teleop(forward=1, left=0, up=0, turn=0))
        _sent(rig, velocity=True, what="velocity setpoints")
        renewed = rig.bus.clock()  # the bus stood still since the message
        rig.run(timeout * 0.9)
        rig.fleet.check_deadmen()  # the process loop's periodic check
        assert link.deadman.active and rig.setpoint().type_mask != MASK_POSITION
        rig.run(renewed + timeout + 0.01 - rig.bus.clock())
        rig.fleet.check_deadmen()
        assert not link.deadman.active
        sp = rig.setpoint()
        assert sp.type_mask == MASK_POSITION and sp.position.z == POSE[2]


def test_closing_the_page_holds_the_drone(rig: StationRig) -> None:
    link = rig.link
    with rig.websocket("/ws/telemetry") as ws:
        ws.send(_teleop(forward=0, left=1, up=0, turn=0))
        _sent(rig, velocity=True, what="velocity setpoints")
        assert link.deadman.active
    assert not link.deadman.active  # the handler ended with the page
    assert rig.setpoint().type_mask == MASK_POSITION


def test_bad_and_forbidden_socket_messages_are_answered(rig: StationRig) -> None:
    def error_for(ws, msg) -> str:
        ws.send(msg if isinstance(msg, str | bytes) else json.dumps(msg))
        while True:
            reply = json.loads(ws.recv(timeout=5))
            if reply["type"] == "error":
                return reply["error"]

    with rig.websocket("/ws/telemetry") as ws:
        assert "forward" in error_for(ws, {"type": "teleop", "ns": "drone", "forward": 9})
        assert "unknown message type" in error_for(ws, {"type": "launch"})
        ghost = {"type": "teleop", "ns": "ghost", "forward": 0, "left": 0, "up": 0, "turn": 0}
        assert "no drone" in error_for(ws, ghost)
        assert error_for(ws, "{not json")
        assert error_for(ws, b"\x00binary")  # answered; the socket stays open
        assert "unknown message type" in error_for(ws, {"type": "what"})
    assert not rig.link.deadman.active
    with rig.websocket("/ws/telemetry", headers=REMOTE) as ws:
        assert _telemetry(ws)["role"] == "observer"
        assert "read-only" in error_for(ws, _teleop(forward=1, left=0, up=0, turn=0))
        assert "read-only" in error_for(ws, {"type": "object", "name": "target", "east": 1})
    assert not rig.link.deadman.active
    assert rig.pilot.setpoints() == []  # nothing reached the bus


def test_cross_origin_sockets_are_refused(rig: StationRig) -> None:
    with pytest.raises(WebSocketRefused) as refused:
        rig.websocket("/ws/telemetry", headers={"Origin": "http://evil.example"})
    assert refused.value.code == 1008


def _frame(k: int) -> CompressedImage:
    return CompressedImage(
        header=Header(stamp=1000.0 + k, frame_id="cam_frontal"), data=b"\xff\xd8" + bytes([k])
    )


def _unpack(data: bytes) -> tuple[dict, bytes]:
    n = int.from_bytes(data[:4], "big")
    return json.loads(data[4 : 4 + n]), data[4 + n :]


def test_video_is_latest_only_one_frame_in_flight(rig: StationRig) -> None:
    camera = FakeNode("camera", rig.bus)
    pub = camera.publisher(registry.IMAGE_COMPRESSED, camera="cam_frontal")
    assert not pub.watched()  # nobody watches: the sim would not even encode
    watched = threading.Event()
    pub.on_matching(lambda matching: matching and watched.set())
    with rig.websocket("/ws/video/drone/frontal") as ws:
        assert watched.wait(5), "the station to subscribe once the socket is accepted"
        pub.put(_frame(1))
        header, jpeg = _unpack(ws.recv(timeout=5))
        assert header["ns"] == "drone" and header["camera"] == "frontal"
        assert header["seq"] == 1 and header["stamp"] == 1001.0 and jpeg == _frame(1).data
        for k in range(2, 7):
            pub.put(_frame(k))
        with pytest.raises(TimeoutError):
            ws.recv(timeout=0.3)  # nothing more until the page acknowledges
        ws.send("ack")
        header, jpeg = _unpack(ws.recv(timeout=5))
        assert header["seq"] == 6 and header["stamp"] == 1006.0  # the newest, no backlog
        assert jpeg == _frame(6).data
    assert not pub.watched()  # the last viewer left: unsubscribed


def test_video_of_unknown_camera_or_drone_is_refused(rig: StationRig) -> None:
    for path in ("/ws/video/drone/thermal", "/ws/video/ghost/frontal"):
        with pytest.raises(WebSocketRefused):
            rig.websocket(path)
