"""The station process: the fleet on the bus, the web server beside it.

uvicorn serves the app on its own thread (:mod:`server`); the main thread keeps the Node's
signal handling (SIGINT/SIGTERM -> stop), runs the teleop dead-man at 20 Hz, and a discovery
thread lists the drones online every ``discover_period``.
"""

from __future__ import annotations

import logging
import threading

from dronewrapper.drone import WRAPPER_PORTS
from dronewrapper.msgs import registry
from dronewrapper.runtime.contract import NodeApi
from dronewrapper.runtime.ports import Ports
from dronewrapper_ground_station.access import Access, is_loopback, new_token
from dronewrapper_ground_station.app import create_app
from dronewrapper_ground_station.config import Config
from dronewrapper_ground_station.fleet import TELEMETRY, Fleet
from dronewrapper_ground_station.server import WebServer

log = logging.getLogger("station")

DEADMAN_PERIOD_S = 0.05

PORTS = (
    Ports(
        "station",
        publishes=(registry.SIM_OBJECT_CMD_VEL,),  # sim_objects.py: teleop of sim objects
        subscribes=(
            *(topic for _section, topic, _fields in TELEMETRY),
            registry.IMAGE_COMPRESSED,  # fleet.py: the video a viewer watches
            registry.SIM_OBJECT_POSE,
        ),
        calls=(registry.SIM_WORLD, registry.SIM_WORLD_LOAD, registry.SIM_RESET),
    )
    | WRAPPER_PORTS
)
"""What the station publishes, subscribes to and calls, its drones' DroneWrappers included
(:mod:`dronewrapper.runtime.ports`)."""


def _discover_forever(fleet: Fleet, period: float, stop: threading.Event) -> None:
    while not stop.is_set():
        try:
            fleet.discover()
        except Exception:  # a closing session: the loop ends with the stop
            log.exception("discovery failed")
        stop.wait(period)


def page_url(host: str, port: int, token: str) -> str:
    """The address to open (with the operator token when there is one)."""
    shown = f"[{host}]" if ":" in host else host
    if host in ("0.0.0.0", "::"):
        shown = "HOST"
    return f"http://{shown}:{port}/" + (f"?token={token}" if token else "")


def operator_token(config: Config) -> str:
    """The configured token, a fresh one when serving beyond loopback, or "" (loopback)."""
    return config.token or ("" if is_loopback(config.host) else new_token())


def run(node: NodeApi, config: Config) -> int:
    """Serve the station until SIGINT/SIGTERM."""
    token = operator_token(config)
    fleet = Fleet(node, config)
    server = WebServer(create_app(fleet, config, Access(token)), config.host, config.port)
    discovery = threading.Thread(
        target=_discover_forever,
        args=(fleet, config.discover_period, node.stop_event),
        name="station-discovery",
        daemon=True,
    )
    try:
        try:
            port = server.start()
        except (RuntimeError, OSError) as exc:
            log.error("%s", exc)
            return 1
        discovery.start()
        print(f"station: open {page_url(config.host, port, token)}", flush=True)
        if token:
            print(
                "station: listening beyond loopback; the token above makes a page an operator's "
                "(one-time: a new one at each start); without it a page is read-only.",
                flush=True,
            )
        node.announce()
        while not node.stop_event.wait(DEADMAN_PERIOD_S):
            fleet.check_deadmen()
    finally:
        server.stop()
        node.stop_event.set()
        if discovery.is_alive():
            discovery.join(timeout=3.0)
        fleet.close()
    return 0
