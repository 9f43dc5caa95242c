"""A station served on a free loopback port, over a real Zenoh router, with a stand-in bridge.

The stand-in is a real Zenoh node in namespace ``drone`` named ``bridge_test`` (so the station
discovers it by its liveliness token): it publishes State, ExtendedState, the local pose and a
simulated object's pose, and answers the arming, set-mode and land services as a bridge would,
refusing what an autopilot would refuse, with a reason.
"""

from __future__ import annotations

import contextlib
import json
import math
import threading
import urllib.error
import urllib.request
from collections.abc import Iterator
from dataclasses import dataclass, field
from typing import Any

from dronewrapper.msgs import registry
from dronewrapper.msgs.geometry import Point, Pose, PoseStamped
from dronewrapper.msgs.mavros import (
    LANDED_STATE_IN_AIR,
    LANDED_STATE_ON_GROUND,
    CommandBool,
    CommandBoolResult,
    CommandTOL,
    CommandTOLResult,
    ExtendedState,
    SetMode,
    SetModeResult,
    State,
)
from dronewrapper.msgs.simulation import WorldState
from dronewrapper.msgs.std import Header
from dronewrapper.runtime.node import Node
from dronewrapper_ground_station.access import Access
from dronewrapper_ground_station.app import create_app
from dronewrapper_ground_station.config import Config
from dronewrapper_ground_station.fleet import Fleet
from dronewrapper_ground_station.server import WebServer
from support import client_node, wait_for

TOKEN = "operator-token-0123456789"
POSE = (1.0, 2.0, 3.0)


@dataclass
class FakeBridge:
    """The stand-in bridge's state (changed by its services)."""

    node: Node
    armed: bool = True
    mode: str = "OFFBOARD"
    landed_state: int = LANDED_STATE_IN_AIR
    requests: list[Any] = field(default_factory=list)

    def arming(self, req: CommandBool) -> CommandBoolResult:
        self.requests.append(req)
        if not req.value and self.landed_state == LANDED_STATE_IN_AIR:
            return CommandBoolResult(success=False, result=4, message="disarming denied in flight")
        self.armed = req.value
        return CommandBoolResult(success=True, result=0)

    def set_mode(self, req: SetMode) -> SetModeResult:
        self.requests.append(req)
        if req.custom_mode not in ("OFFBOARD", "AUTO.LOITER", "AUTO.LAND"):
            return SetModeResult(
                mode_sent=False, result=4, message=f"unknown mode {req.custom_mode}"
            )
        self.mode = req.custom_mode
        return SetModeResult(mode_sent=True, result=0)

    def land(self, req: CommandTOL) -> CommandTOLResult:
        self.requests.append(req)
        self.landed_state, self.armed, self.mode = LANDED_STATE_ON_GROUND, False, "AUTO.LAND"
        return CommandTOLResult(success=True, result=0)

    def publish_forever(self, stop: threading.Event) -> None:
        state = self.node.publisher(registry.STATE)
        extended = self.node.publisher(registry.EXTENDED_STATE)
        pose = self.node.publisher(registry.LOCAL_POSE)
        target = self.node.publisher(registry.SIM_OBJECT_POSE, name="target")
        x, y, z = POSE
        while not stop.wait(0.05):
            now = Header(stamp=0.0)
            state.put(State(connected=True, armed=self.armed, mode=self.mode, autopilot="px4"))
            extended.put(ExtendedState(landed_state=self.landed_state))
            pose.put(PoseStamped(header=now, pose=Pose(position=Point(x=x, y=y, z=z))))
            target.put(PoseStamped(pose=Pose(position=Point(x=5.0, y=-1.0, z=0.0))))


@dataclass
class StationEnv:
    port: int
    fleet: Fleet
    bridge: FakeBridge
    config: Config

    @property
    def base(self) -> str:
        return f"http://127.0.0.1:{self.port}"

    def http(
        self, method: str, path: str, body: Any = None, headers: dict[str, str] | None = None
    ) -> tuple[int, Any, dict[str, str]]:
        """(status, decoded JSON or text, headers) of a real HTTP request on loopback."""
        data = None if body is None else (body if isinstance(body, bytes) else json.dumps(body))
        req = urllib.request.Request(
            self.base + path,
            data=data.encode() if isinstance(data, str) else data,
            method=method,
            headers={"Content-Type": "application/json", **(headers or {})},
        )
        try:
            with urllib.request.urlopen(req, timeout=30) as reply:
                status, raw, hdrs = reply.status, reply.read(), dict(reply.headers)
        except urllib.error.HTTPError as exc:
            status, raw, hdrs = exc.code, exc.read(), dict(exc.headers)
        try:
            return status, json.loads(raw), hdrs
        except ValueError:
            return status, raw.decode(errors="replace"), hdrs


@contextlib.contextmanager
def station_env(router: str, *, simulator: bool = False, **config: Any) -> Iterator[StationEnv]:
    """The stand-in bridge and a station (token ``TOKEN``) on ``router``; with ``simulator``,
    the stand-in also answers the simulator's world query (the page asks for it)."""
    cfg = Config(port=0, command_timeout=5.0, **config)
    stop = threading.Event()
    with client_node(router, name="bridge_test", mode="client") as bridge_node:
        bridge = FakeBridge(bridge_node)
        bridge_node.serve(registry.ARMING, bridge.arming)
        bridge_node.serve(registry.SET_MODE, bridge.set_mode)
        bridge_node.serve(registry.LAND, bridge.land)
        if simulator:
            world = WorldState(scenario="beacon_static", objects=["target"], available=["empty"])
            bridge_node.serve(registry.SIM_WORLD, lambda _: world)
        publisher = threading.Thread(target=bridge.publish_forever, args=(stop,), daemon=True)
        publisher.start()
        bridge_node.announce()
        with client_node(router, name="station", mode="client") as station_node:
            fleet = Fleet(station_node.session, cfg)
            server = WebServer(create_app(fleet, cfg, Access(TOKEN)), "127.0.0.1", 0)
            try:
                wait_for(lambda: fleet.discover() or "drone" in fleet.links, 10, what="discovery")
                link = fleet.get("drone")
                wait_for(lambda: link.value("pose") and link.value("state"), 10, what="telemetry")
                wait_for(link.drone.is_connected, 10, what="the SDK to see the bridge")
                wait_for(lambda: fleet.objects.snapshot(), 10, what="object poses")
                yield StationEnv(server.start(), fleet, bridge, cfg)
            finally:
                stop.set()
                publisher.join(2)
                server.stop()
                fleet.close()


def assert_close(a: float, b: float, tol: float = 1e-6) -> None:
    assert math.isclose(a, b, abs_tol=tol), f"{a} != {b}"
