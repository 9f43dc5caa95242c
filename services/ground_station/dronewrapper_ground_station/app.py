"""The station's HTTP and WebSocket routes (a Starlette ASGI app, served by uvicorn).

    GET  /                                  the page (static files under /static)
    GET  /api/session                       who you are (operator / observer) and the limits
    GET  /api/drones                        the drones online with their health
    GET  /api/drones/{ns}                   one drone's telemetry snapshot
    POST /api/drones/{ns}/{command}         arm, disarm, takeoff {height}, land, hold,
                                            mode {mode}, goto {x, y}      (operators only)
    GET  /api/objects                       the simulated world's objects and their poses
    POST /api/objects/{name}/velocity       {east, north} in [-1, 1]     (operators only)
    WS   /ws/telemetry                      snapshots at telemetry_rate_hz; takes teleop,
                                            teleop_release and object messages
    WS   /ws/video/{ns}/{camera}            JPEG frames, one in flight: the page acks each

Operators send their token as ``X-Station-Token`` (HTTP) or ``?token=`` (WebSocket). Every
state-changing request and every WebSocket must come from the station's own origin.
"""

from __future__ import annotations

import asyncio
import contextlib
import json
import logging
from collections.abc import Callable
from pathlib import Path
from typing import Any

import msgspec
from starlette.applications import Starlette
from starlette.concurrency import run_in_threadpool
from starlette.requests import HTTPConnection, Request
from starlette.responses import FileResponse, JSONResponse, Response
from starlette.routing import Mount, Route, WebSocketRoute
from starlette.staticfiles import StaticFiles
from starlette.websockets import WebSocket, WebSocketDisconnect

from dronewrapper import errors
from dronewrapper.runtime.errors import ServiceError, ServiceUnavailable
from dronewrapper_ground_station import requests
from dronewrapper_ground_station.access import OPERATOR, Access
from dronewrapper_ground_station.config import Config
from dronewrapper_ground_station.fleet import CAMERAS, DroneLink, Fleet
from dronewrapper_ground_station.frames import pack

log = logging.getLogger("station")

STATIC = Path(__file__).with_name("static")
MODES = ("OFFBOARD", "AUTO.LOITER", "AUTO.LAND", "AUTO.RTL", "POSCTL", "ALTCTL", "MANUAL")
SECURITY_HEADERS = {
    "Content-Security-Policy": (
        "default-src 'self'; img-src 'self' blob: data:; connect-src 'self'; "
        "frame-ancestors 'none'; base-uri 'none'; form-action 'none'"
    ),
    "X-Content-Type-Options": "nosniff",
    "Referrer-Policy": "no-referrer",
    "Cache-Control": "no-store",
}
_json = msgspec.json.Encoder()  # NaN and inf become null


def _role(conn: HTTPConnection, access: Access) -> str:
    token = conn.headers.get("x-station-token") or conn.query_params.get("token") or ""
    client = conn.client.host if conn.client else ""
    return access.role(client, conn.headers.get("host", ""), token)


def _error(status: int, message: str, **extra: Any) -> JSONResponse:
    return JSONResponse({"ok": False, "error": message, **extra}, status, SECURITY_HEADERS)


def _ok(body: Any) -> Response:
    return Response(_json.encode(body), 200, SECURITY_HEADERS, media_type="application/json")


async def _receive_text(ws: WebSocket) -> str:
    """The next text message ("" for a binary one). Raises WebSocketDisconnect at the end."""
    message = await ws.receive()
    if message["type"] == "websocket.disconnect":
        raise WebSocketDisconnect(message.get("code", 1000))
    return message.get("text") or ""


def _command_action(link: DroneLink, command: str, body: Any, config: Config) -> Callable[[], None]:
    """The blocking call for ``command`` with its validated arguments (BadRequest if not)."""
    if command == "takeoff":
        height = requests.number(body, "height", 0.5, config.takeoff_max)
        return lambda: link.takeoff(height)
    if command == "goto":
        x, y = requests.goto(body, config.goto_max_distance)
        return lambda: link.goto(x, y)
    if command == "mode":
        mode = requests.text(body, "mode", 32)
        if mode not in MODES and not mode.replace(".", "").replace("_", "").isalnum():
            raise requests.BadRequest(f"mode {mode!r} is not a mode name")
        return lambda: link.set_mode(mode)
    if command == "upload_plan":
        plan = body.get("plan") if isinstance(body, dict) else None
        if not isinstance(plan, dict):
            raise requests.BadRequest("plan must be a QGroundControl .plan document (an object)")
        return lambda: link.upload_plan(plan)
    simple = {
        "arm": link.arm,
        "disarm": link.disarm,
        "land": link.land,
        "hold": link.hold,
        "start_mission": link.start_mission,
        "pause_mission": link.pause_mission,
        "rtl": link.return_to_launch,
        "reset": link.reset,
    }
    if command in simple:
        return simple[command]
    raise KeyError(command)


def create_app(fleet: Fleet, config: Config, access: Access) -> Starlette:
    """The station's ASGI app over ``fleet``."""

    async def index(_: Request) -> Response:
        return FileResponse(STATIC / "index.html", headers=SECURITY_HEADERS)

    async def session(request: Request) -> Response:
        return _ok(
            {
                "role": _role(request, access),
                "limits": msgspec.to_builtins(config.teleop),
                "takeoff_max": config.takeoff_max,
                "goto_max_distance": config.goto_max_distance,
                "telemetry_rate_hz": config.telemetry_rate_hz,
                "modes": MODES,
                "cameras": list(CAMERAS),
                "token_required": bool(access.token),
            }
        )

    async def drones(_: Request) -> Response:
        return _ok(fleet.summary())

    async def drone(request: Request) -> Response:
        ns = request.path_params["ns"]
        if ns not in fleet.links:
            return _error(404, f"no drone {ns!r}")
        return _ok(fleet.get(ns).snapshot())

    def _operator_check(request: Request) -> JSONResponse | None:
        if not access.same_origin(request.headers.get("origin"), request.headers.get("host", "")):
            return _error(403, "cross-origin request refused")
        if _role(request, access) != OPERATOR:
            return _error(403, "read-only page: commands need the operator token")
        return None

    async def _body(request: Request) -> Any:
        raw = await request.body()
        if not raw.strip():
            return {}
        try:
            return json.loads(raw)
        except ValueError as exc:
            raise requests.BadRequest(f"body is not JSON: {exc}") from None

    async def command(request: Request) -> Response:
        refused = _operator_check(request)
        if refused:
            return refused
        ns, name = request.path_params["ns"], request.path_params["command"]
        if ns not in fleet.links:
            return _error(404, f"no drone {ns!r}")
        link = fleet.get(ns)
        try:
            action = _command_action(link, name, await _body(request), config)
        except requests.BadRequest as exc:
            return _error(400, f"{name}: {exc}")
        except KeyError:
            return _error(404, f"unknown command {name!r}")
        started = link.clock.monotonic()
        try:
            await run_in_threadpool(action)
        except errors.CommandRefused as exc:
            return _error(409, str(exc), reason=exc.reason)
        except errors.Timeout as exc:
            return _error(504, str(exc))
        except errors.NotConnected as exc:
            return _error(503, str(exc))
        except (errors.NoData, errors.InvalidArgument, RuntimeError) as exc:
            return _error(409, str(exc))
        seconds = link.clock.monotonic() - started
        log.info("%s %s done in %.1f s", ns, name, seconds)
        return _ok({"ok": True, "command": name, "seconds": seconds})

    async def land_all(request: Request) -> Response:
        refused = _operator_check(request)
        if refused:
            return refused
        outcomes = await run_in_threadpool(fleet.land_all)
        log.info("land all: %s", ", ".join(f"{ns} {what}" for ns, what in outcomes.items()))
        landed = all(what == "landed" for what in outcomes.values())
        return _ok({"ok": landed, "drones": outcomes})

    async def objects(_: Request) -> Response:
        return _ok(fleet.objects.snapshot())

    async def object_velocity(request: Request) -> Response:
        refused = _operator_check(request)
        if refused:
            return refused
        try:
            east, north = requests.object_velocity(await _body(request), config.object_speed)
            fleet.objects.move(request.path_params["name"], east, north)
        except requests.BadRequest as exc:
            return _error(400, str(exc))
        except KeyError as exc:
            return _error(404, str(exc.args[0]))
        return _ok({"ok": True})

    async def world(_: Request) -> Response:
        # No simulator is the normal case of a real aircraft: a 200 that says so (the page
        # polls this; an error status would be logged by every browser as a failure)
        try:
            state = await asyncio.to_thread(fleet.objects.world)
        except ServiceUnavailable as exc:
            return _ok({"simulator": False, "message": f"no simulator answers: {exc}"})
        return _ok({"simulator": True, **msgspec.to_builtins(state)})

    async def world_load(request: Request) -> Response:
        refused = _operator_check(request)
        if refused:
            return refused
        try:
            scenario = requests.scenario_name(await _body(request))
            state = await asyncio.to_thread(fleet.objects.load, scenario)
        except requests.BadRequest as exc:
            return _error(400, str(exc))
        except ServiceUnavailable as exc:
            return _error(503, f"no simulator answers: {exc}")
        except ServiceError as exc:
            return _error(400 if exc.code == "bad_request" else 409, exc.message)
        log.info("world loaded: %s", state.scenario)
        return _ok({"ok": True, **msgspec.to_builtins(state)})

    async def _accept(ws: WebSocket) -> str | None:
        if not access.same_origin(ws.headers.get("origin"), ws.headers.get("host", "")):
            await ws.close(code=1008, reason="cross-origin WebSocket refused")
            return None
        await ws.accept()
        return _role(ws, access)

    def _on_message(msg: Any, role: str, owner: object) -> str | None:
        """Handle one page message; an error text for the page, or None."""
        kind = msg.get("type") if isinstance(msg, dict) else None
        if kind not in ("teleop", "teleop_release", "object"):
            return f"unknown message type {kind!r}"
        if role != OPERATOR:
            return "read-only page: commands need the operator token"
        if kind == "object":
            east, north = requests.object_velocity(msg, config.object_speed)
            fleet.objects.move(requests.text(msg, "name"), east, north)
            return None
        ns = requests.text(msg, "ns")
        if ns not in fleet.links:
            return f"no drone {ns!r}"
        link = fleet.get(ns)
        if kind == "teleop_release":
            link.release(owner)
        else:
            link.teleop(requests.sticks(msg, config.teleop), owner)
        return None

    async def telemetry(ws: WebSocket) -> None:
        role = await _accept(ws)
        if role is None:
            return
        owner = object()  # this page, as the owner of the teleop it starts
        period = 1.0 / config.telemetry_rate_hz

        async def push() -> None:
            while True:
                payload = {
                    "type": "telemetry",
                    "t": fleet.clock.time(),
                    "role": role,
                    "router": fleet.router(),
                    "fleet": fleet.summary(),
                    "drones": {ns: link.snapshot() for ns, link in list(fleet.links.items())},
                    "objects": fleet.objects.snapshot(),
                }
                await ws.send_bytes(_json.encode(payload))
                await asyncio.sleep(period)

        pusher = asyncio.create_task(push())
        try:
            while True:
                text = await _receive_text(ws)
                try:
                    error = _on_message(json.loads(text), role, owner)
                except (ValueError, KeyError, errors.DroneError) as exc:
                    error = str(exc)
                if error:
                    await ws.send_text(json.dumps({"type": "error", "error": error}))
        except (WebSocketDisconnect, RuntimeError):
            pass
        finally:
            pusher.cancel()
            with contextlib.suppress(asyncio.CancelledError, Exception):
                await pusher
            fleet.release_owner(owner)  # a lost page stops its drones: they hold

    async def video(ws: WebSocket) -> None:
        ns, camera = ws.path_params["ns"], ws.path_params["camera"]
        if ns not in fleet.links or camera not in CAMERAS:
            await ws.close(code=1008, reason=f"no camera {camera!r} on drone {ns!r}")
            return
        if await _accept(ws) is None:
            return
        link = fleet.get(ns)
        slot = link.watch(camera)
        loop = asyncio.get_running_loop()
        new_frame, acked = asyncio.Event(), asyncio.Event()
        acked.set()

        def notify() -> None:
            with contextlib.suppress(RuntimeError):  # the loop is closing
                loop.call_soon_threadsafe(new_frame.set)

        slot.listen(notify)
        if slot.value is not None:
            new_frame.set()

        async def send_frames() -> None:
            sent_seq = 0
            while True:
                await acked.wait()
                await new_frame.wait()
                new_frame.clear()
                got = slot.take(0.0, sent_seq)
                if got is None:
                    continue
                sent_seq, frame = got
                header = {
                    "ns": ns,
                    "camera": camera,
                    "seq": sent_seq,
                    "stamp": frame.header.stamp,
                    "sent": link.clock.time(),
                    "held": slot.age(),
                }
                acked.clear()
                await ws.send_bytes(pack(frame, json.dumps(header).encode()))

        sender = asyncio.create_task(send_frames())
        try:
            while True:
                if await _receive_text(ws) == "ack":
                    acked.set()
        except (WebSocketDisconnect, RuntimeError):
            pass
        finally:
            slot.unlisten(notify)
            sender.cancel()
            with contextlib.suppress(asyncio.CancelledError, Exception):
                await sender
            link.unwatch(camera)

    routes = [
        Route("/", index),
        Route("/api/session", session),
        Route("/api/drones", drones),
        Route("/api/drones/{ns}", drone),
        Route("/api/drones/{ns}/{command}", command, methods=["POST"]),
        Route("/api/fleet/land", land_all, methods=["POST"]),
        Route("/api/objects", objects),
        Route("/api/objects/{name}/velocity", object_velocity, methods=["POST"]),
        Route("/api/world", world),
        Route("/api/world", world_load, methods=["POST"]),
        WebSocketRoute("/ws/telemetry", telemetry),
        WebSocketRoute("/ws/video/{ns}/{camera}", video),
        Mount("/static", StaticFiles(directory=STATIC), name="static"),
    ]
    return Starlette(routes=routes)
