"""``dronewrapper sim --aircraft tello``: set up the address (or the namespace) and run."""

from __future__ import annotations

import logging
import os

from dronewrapper.runtime.contract import NodeApi
from dronewrapper_sim.config import SimConfig
from dronewrapper_sim.tello.config import default_address
from dronewrapper_sim.tello.server import COMMAND_PORT, TelloServer
from dronewrapper_sim.udp import bind_udp
from dronewrapper_sim.world.scenario import Scenario
from dronewrapper_sim.world_process import run_world

log = logging.getLogger("sim.tello")


def run_tello(node: NodeApi, config: SimConfig, scenario: Scenario) -> int:
    """Run the simulated Tello on ``node`` until SIGINT/SIGTERM. Exit codes: 0 clean stop,
    1 an address (the command's or the video's) cannot be bound, 2 ``--netns`` without
    root."""
    if config.netns:
        if os.geteuid() != 0:
            log.error("--netns needs root (it creates a network namespace and a veth pair)")
            return 2
        from dronewrapper_sim.tello.netns import TelloNamespace

        try:
            namespace = TelloNamespace.create(config.instance, config.tello.netns_subnet)
        except (OSError, RuntimeError) as exc:
            log.error("cannot create the network namespace: %s", exc)
            return 1
        address = config.address or namespace.drone_address
        make_socket = namespace.run_inside
    else:
        namespace = None
        address = config.address or default_address(config.instance)

        def make_socket(fn):
            return fn()

    try:
        try:
            sock = make_socket(lambda: bind_udp(address, COMMAND_PORT))
        except OSError as exc:
            log.error("cannot bind udp %s:%d: %s", address, COMMAND_PORT, exc)
            return 1
        if namespace is not None:
            log.info("network namespace: %s", namespace.describe())

        def make() -> TelloServer:
            server = TelloServer(config.tello, scenario, node, sock, seed=config.seed)
            if config.tello.video:
                from dronewrapper_sim.tello.video import VideoStreamer

                try:
                    server.video = VideoStreamer(server, config.sprites, make_socket)
                except BaseException:
                    server.close()
                    raise
            return server

        server = run_world(node, make, log)
        if server is None:
            return 1
        log.info(
            "stopped: %d datagrams in, %d replies, %d states out",
            server.datagrams,
            server.replies,
            server.states,
        )
        return 0
    finally:
        if namespace is not None:
            namespace.remove()
