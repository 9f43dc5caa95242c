"""Helper for the SDK's simulator tests: run compose/sim_iris.yaml on free loopback ports.

``sim_graph`` starts ``dronewrapper up compose/sim_iris.yaml`` (its own router on a free port, or
``use_router=True`` to join a running one) with free UDP ports, waits until the namespace's
bridge is alive, yields the router endpoint, and stops the graph with SIGINT at the end.
"""

from __future__ import annotations

import contextlib
import socket
import time
from collections.abc import Iterator
from pathlib import Path

from dronewrapper import NotConnected, list_drones
from support import Process, free_endpoint, free_port, python_module

START_TIMEOUT_S = 60.0


@contextlib.contextmanager
def sim_graph(
    log_dir: Path,
    ns: str = "drone",
    *,
    router: str | None = None,
    use_router: bool = False,
    extra: tuple[str, ...] = (),
) -> Iterator[tuple[str, Process]]:
    """Run the simulated Iris + bridge in namespace ``ns``; yields (router endpoint, process)."""
    router = router or free_endpoint()
    argv = python_module(
        "dronewrapper",
        "up",
        "compose/sim_iris.yaml",
        "--router",
        router,
        "--ns",
        ns,
        "--var",
        f"onboard_port={free_port(socket.SOCK_DGRAM)}",
        "--var",
        f"gcs_port={free_port(socket.SOCK_DGRAM)}",
        *(["--use-router"] if use_router else []),
        *extra,
    )
    proc = Process(argv, log_dir / f"sim_iris-{ns}.log")
    try:
        deadline = time.monotonic() + START_TIMEOUT_S
        while True:
            assert proc.alive(), f"graph exited early:\n{proc.output()[-4000:]}"
            try:
                if ns in list_drones(router, timeout=1.0):
                    break
            except NotConnected:
                pass  # the launcher's router is not up yet
            assert time.monotonic() < deadline, f"no bridge in {ns}:\n{proc.output()[-4000:]}"
            time.sleep(0.3)
        yield router, proc
    finally:
        proc.stop(30)
