"""Helper for the SDK's simulator tests: run compose/sim_iris.yaml on free loopback ports.

``sim_graph`` starts ``dronewrapper up compose/sim_iris.yaml`` (its own router on a free port)
with free UDP ports, waits until the namespace's bridge is alive, yields the router endpoint,
and stops the graph with SIGINT at the end.
"""

from __future__ import annotations

import contextlib
import socket
from collections.abc import Iterator, Sequence
from pathlib import Path

from support import Process, free_endpoint, free_port, python_module, wait_for_bridges

START_TIMEOUT_S = 60.0


def _start(log_dir: Path, ns: str, router: str, variables: Sequence[str] = ()) -> Process:
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
        *(arg for variable in variables for arg in ("--var", variable)),
    )
    return Process(argv, log_dir / f"sim_iris-{ns}.log")


@contextlib.contextmanager
def sim_graph(
    log_dir: Path, ns: str = "drone", variables: Sequence[str] = ()
) -> Iterator[tuple[str, Process]]:
    """Run the simulated Iris + bridge + a router (``variables``: the graph's ``KEY=VALUE``
    variables, e.g. ``command_lease=true``); yields (router endpoint, graph process)."""
    router = free_endpoint()
    proc = _start(log_dir, ns, router, variables=variables)
    try:
        wait_for_bridges(router, {ns: proc}, START_TIMEOUT_S)
        yield router, proc
    finally:
        proc.stop(30)
