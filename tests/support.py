"""Test helpers: free loopback ports, a real Zenoh router, service processes, bounded waits."""

from __future__ import annotations

import contextlib
import os
import signal
import socket
import subprocess
import sys
import threading
import time
from collections.abc import Callable, Iterator, Sequence
from pathlib import Path
from typing import TypeVar

import zenoh

from dronewrapper import NotConnected, list_drones
from dronewrapper.router import router_options
from dronewrapper.runtime import Node, ZenohOptions
from dronewrapper.runtime.children import die_with_parent
from dronewrapper.runtime.options import zenoh_config
from dronewrapper_compose.ports import free_port

T = TypeVar("T")

REPO = Path(__file__).resolve().parents[1]
ASSETS = REPO / "assets"
YOLOX_NANO = ASSETS / "models" / "yolox_nano.onnx"
SPRITES = ASSETS / "sprites"


def loopback_udp(timeout: float) -> socket.socket:
    """A UDP socket bound to a free loopback port; a read gives up after ``timeout`` s."""
    sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    sock.bind(("127.0.0.1", 0))
    sock.settimeout(timeout)
    return sock


def free_endpoint() -> str:
    """A free ``tcp/127.0.0.1:PORT`` Zenoh endpoint."""
    return f"tcp/127.0.0.1:{free_port()}"


@contextlib.contextmanager
def zenoh_router(endpoint: str | None = None) -> Iterator[str]:
    """Run a real Zenoh router (a router-mode session, as ``dronewrapper router`` opens) on a
    loopback endpoint.

    Like every router the runtime opens, it has no scouting delay (nothing to scout with
    multicast off), so starting one costs no 0.5 s wait.
    """
    endpoint = endpoint or free_endpoint()
    session = zenoh.open(zenoh_config(router_options([endpoint])))
    try:
        yield endpoint
    finally:
        session.close()


def client_node(
    endpoint: str,
    name: str = "test",
    namespace: str = "drone",
    *,
    mode: str = "peer",
    options_extra: dict | None = None,
    **kw,
) -> Node:
    """A Node for the test process itself, connected to ``endpoint`` (no signal handlers;
    ``options_extra``: more ZenohOptions fields).

    ``mode="client"`` opens at once; a peer waits Zenoh's scouting delay (0.5 s) whenever
    other peers are already on the router.
    """
    options = ZenohOptions(
        mode=mode, connect=[endpoint], namespace=namespace, name=name, **(options_extra or {})
    )
    return Node(name, options, handle_signals=False, **kw)


def wait_for(
    predicate: Callable[[], T], timeout: float, *, interval: float = 0.05, what: str = ""
) -> T:
    """Poll ``predicate`` until it returns a truthy value; raise AssertionError on timeout."""
    deadline = time.monotonic() + timeout
    while True:
        value = predicate()
        if value:
            return value
        if time.monotonic() >= deadline:
            raise AssertionError(f"timed out after {timeout:g} s waiting for {what or predicate}")
        time.sleep(interval)


class Process:
    """A child process with its output captured to a file; stopped with SIGINT, then killed."""

    def __init__(
        self,
        argv: Sequence[str],
        log_path: Path,
        env: dict[str, str] | None = None,
        cwd: Path = REPO,
    ):
        self.argv = list(argv)
        self.log_path = log_path
        self._log = open(log_path, "wb")  # noqa: SIM115 - closed in stop()
        self.proc = subprocess.Popen(
            self.argv,
            stdout=self._log,
            stderr=subprocess.STDOUT,
            env={**os.environ, "PYTHONUNBUFFERED": "1", **(env or {})},
            cwd=cwd,
            preexec_fn=die_with_parent,  # a killed test run leaves no sim or bridge behind
        )

    def output(self) -> str:
        return self.log_path.read_text(errors="replace")

    def alive(self) -> bool:
        return self.proc.poll() is None

    def stop(self, timeout: float = 10.0) -> int:
        """SIGINT, wait up to ``timeout``, then SIGKILL; returns the exit status."""
        if self.proc.poll() is None:
            self.proc.send_signal(signal.SIGINT)
            try:
                self.proc.wait(timeout)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait(5)
        self._log.close()
        return self.proc.returncode


def wait_for_bridges(router: str, graphs: dict[str, Process], timeout_s: float = 60.0) -> None:
    """Wait until the bridge of each namespace in ``graphs`` is online on ``router``; fails at
    once when a graph process exits, and after ``timeout_s`` with the silent graphs' logs."""
    deadline = time.monotonic() + timeout_s
    while True:
        for ns, proc in graphs.items():
            assert proc.alive(), f"graph {ns} exited early:\n{proc.output()[-4000:]}"
        try:
            online = list_drones(router, timeout=1.0)
        except NotConnected:
            online = []  # the graph's router is not up yet
        missing = [ns for ns in graphs if ns not in online]
        if not missing:
            return
        logs = "\n".join(graphs[ns].output()[-2000:] for ns in missing)
        assert time.monotonic() < deadline, f"no bridge in {', '.join(missing)}:\n{logs}"
        time.sleep(0.3)


def station_process(router: str, log_dir: Path) -> tuple[Process, str]:
    """The ground station as its own process on a free loopback port, connected to ``router``
    (its log ``station.log`` in ``log_dir``): the process and its page's URL, served once
    :func:`station_serving` returned."""
    port = free_port()
    station = Process(
        python_module("dronewrapper_ground_station", "--connect", router, "--port", str(port)),
        log_dir / "station.log",
    )
    return station, f"http://127.0.0.1:{port}/"


def station_serving(station: Process) -> None:
    """Wait (30 s at most) until ``station`` says its page is open."""
    wait_for(lambda: "station: open" in station.output(), 30, what="the station to serve")


def start_daemons(*targets: Callable[[], object]) -> list[threading.Thread]:
    """A started daemon thread for each of ``targets`` (a test peer's loops)."""
    threads = [threading.Thread(target=target, daemon=True) for target in targets]
    for thread in threads:
        thread.start()
    return threads


def stop_daemons(stop: threading.Event, threads: list[threading.Thread]) -> None:
    """Set ``stop`` (what the loops of ``threads`` watch) and wait up to 2 s for each."""
    stop.set()
    for thread in threads:
        thread.join(2)


def python_module(module: str, *args: str) -> list[str]:
    """argv running ``python -m module args`` with this interpreter."""
    return [sys.executable, "-m", module, *args]
