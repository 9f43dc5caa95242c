"""A station served on a free loopback port, over a real Zenoh router, with a stand-in bridge.

The stand-in is the shared fake bridge (tests/fake_bridge.py), flying in OFFBOARD at ``POSE``
in namespace ``drone`` named ``bridge_test`` (the station discovers it by its liveliness
token): it publishes the bridge's telemetry and a simulated object's pose, and answers the
bridge's services as a bridge would, refusing what an autopilot would refuse, with a reason.
"""

from __future__ import annotations

import contextlib
import json
import math
import urllib.error
import urllib.request
from collections.abc import Iterator
from dataclasses import dataclass
from typing import Any

from dronewrapper.msgs import registry
from dronewrapper.msgs.simulation import WorldState
from dronewrapper_ground_station.access import Access
from dronewrapper_ground_station.app import create_app
from dronewrapper_ground_station.config import Config
from dronewrapper_ground_station.fleet import Fleet
from dronewrapper_ground_station.server import WebServer
from fake_bridge import FakeBridge
from support import client_node, wait_for

TOKEN = "operator-token-0123456789"
POSE = (1.0, 2.0, 3.0)


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
    target = {"target": (5.0, -1.0, 0.0)}
    bridge = FakeBridge(router, flying=True, position=POSE, objects=target, name="bridge_test")
    if simulator:
        world = WorldState(scenario="beacon_static", objects=["target"], available=["empty"])
        bridge.node.serve(registry.SIM_WORLD, lambda _: world)
    try:
        with client_node(router, name="station", mode="client") as station_node:
            fleet = Fleet(station_node, cfg)
            server = WebServer(create_app(fleet, cfg, Access(TOKEN)), "127.0.0.1", 0)
            try:
                wait_for(lambda: fleet.discover() or "drone" in fleet.links, 10, what="discovery")
                link = fleet.get("drone")
                wait_for(lambda: link.value("pose") and link.value("state"), 10, what="telemetry")
                wait_for(link.drone.is_connected, 10, what="the SDK to see the bridge")
                wait_for(lambda: fleet.objects.snapshot(), 10, what="object poses")
                yield StationEnv(server.start(), fleet, bridge, cfg)
            finally:
                server.stop()
                fleet.close()
    finally:
        bridge.close()


def assert_close(a: float, b: float, tol: float = 1e-6) -> None:
    assert math.isclose(a, b, abs_tol=tol), f"{a} != {b}"
