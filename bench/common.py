"""Small helpers shared by the benchmarks: percentiles, tables, JSON results, machine facts,
call timings, CPU time of a process, stopping a child process, and a Zenoh router on
loopback."""

from __future__ import annotations

import contextlib
import json
import os
import platform
import signal
import subprocess
import threading
import time
from collections.abc import Callable, Iterator, Sequence
from pathlib import Path
from typing import Any, Protocol, TypeVar

import numpy as np


class _Closes(Protocol):
    def close(self) -> None: ...


P = TypeVar("P", bound=_Closes)

RESULTS = Path(__file__).resolve().parent / "results"
CLK_TCK = os.sysconf("SC_CLK_TCK")
"""Kernel clock ticks per second: the unit of the CPU times in ``/proc/PID/stat``."""


def percentiles(values_s: Sequence[float]) -> dict[str, float]:
    """p50/p90/p99/max of durations given in seconds, returned in milliseconds."""
    arr = np.asarray(values_s, dtype=float) * 1e3
    if arr.size == 0:
        return {"n": 0}
    return {
        "n": int(arr.size),
        "p50_ms": float(np.percentile(arr, 50)),
        "p90_ms": float(np.percentile(arr, 90)),
        "p99_ms": float(np.percentile(arr, 99)),
        "max_ms": float(arr.max()),
    }


def call_times_ms(fn: Callable[[], object], runs: int, warmup: int = 5) -> list[float]:
    """Wall time of each of ``runs`` calls of ``fn()`` (ms), after ``warmup`` calls untimed."""
    for _ in range(warmup):
        fn()
    times = []
    for _ in range(runs):
        start = time.perf_counter()
        fn()
        times.append((time.perf_counter() - start) * 1e3)
    return times


def machine() -> dict[str, object]:
    """Facts about the machine the figures were taken on."""
    load = os.getloadavg()
    return {
        "cpus": os.cpu_count(),
        "processor": platform.processor() or platform.machine(),
        "python": platform.python_version(),
        "loadavg_at_end": [round(x, 2) for x in load],
        "time": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()),
    }


def print_table(title: str, header: Sequence[str], rows: Sequence[Sequence[object]]) -> None:
    """Print a plain-text table."""
    cells = [[str(c) for c in header]] + [[_fmt(c) for c in row] for row in rows]
    widths = [max(len(r[i]) for r in cells) for i in range(len(header))]
    print(f"\n{title}")
    for i, row in enumerate(cells):
        print("  " + "  ".join(c.rjust(w) if j else c.ljust(w) for j, (c, w) in
                               enumerate(zip(row, widths, strict=True))))  # fmt: skip
        if i == 0:
            print("  " + "  ".join("-" * w for w in widths))


def _fmt(value: object) -> str:
    if isinstance(value, float):
        return f"{value:.3f}" if abs(value) < 100 else f"{value:.0f}"
    return str(value)


def write_results(name: str, data: dict[str, object]) -> Path:
    """Write ``bench/results/NAME.json`` with the machine facts added."""
    RESULTS.mkdir(parents=True, exist_ok=True)
    path = RESULTS / f"{name}.json"
    path.write_text(json.dumps({"machine": machine(), **data}, indent=2) + "\n")
    print(f"\nwrote {path}")
    return path


def cpu_seconds(pid: int) -> float:
    """User + system CPU time of process ``pid`` so far (s), from ``/proc/PID/stat``.

    Raises:
        OSError: the process is gone.
    """
    fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / CLK_TCK  # utime, stime (fields 14, 15)


def stop_process(proc: subprocess.Popen, sig: int = signal.SIGINT, timeout_s: float = 10.0) -> None:
    """Send ``sig`` to ``proc`` and wait up to ``timeout_s`` for it to exit; kill it (and reap
    it, up to 5 s) if it has not."""
    proc.send_signal(sig)
    try:
        proc.wait(timeout_s)
    except subprocess.TimeoutExpired:
        proc.kill()
        proc.wait(5)


def free_endpoint() -> str:
    """A Zenoh TCP endpoint on a loopback port that is free right now."""
    from dronewrapper_compose.ports import free_port

    return f"tcp/127.0.0.1:{free_port('tcp')}"


class LoopbackRouter:
    """A Zenoh router in a daemon thread of this process, listening on ``endpoint`` (a free
    loopback TCP port unless one is given)."""

    def __init__(self, endpoint: str | None = None) -> None:
        from dronewrapper.router import router_options, run_router

        self.endpoint = endpoint or free_endpoint()
        self._stop, self._ready = threading.Event(), threading.Event()
        self._thread = threading.Thread(
            target=run_router,
            args=(router_options([self.endpoint]), self._stop, self._ready),
            daemon=True,
        )

    def start(self, timeout_s: float = 10.0) -> bool:
        """Start the router; True once it listens, False if it did not within ``timeout_s``."""
        self._thread.start()
        return self._ready.wait(timeout_s)

    def stop(self, timeout_s: float = 10.0) -> None:
        """Close the router and wait up to ``timeout_s`` for its thread to end."""
        self._stop.set()
        self._thread.join(timeout_s)


def started_router() -> LoopbackRouter:
    """A :class:`LoopbackRouter` that listens; the bench ends (status 1) when it does not."""
    router = LoopbackRouter()
    if not router.start():
        raise SystemExit("router did not start")
    return router


@contextlib.contextmanager
def probed_graph(launcher: Any, router: str, make_probe: Callable[[Any, str], P]) -> Iterator[P]:
    """Start ``launcher``'s graph and ``make_probe(session, ns)`` on a client session to
    ``router``; on the way out the probe and the session are closed and the graph stopped."""
    from dronewrapper.runtime.node import open_session
    from dronewrapper.runtime.options import ZenohOptions

    session = probe = None
    try:
        launcher.start()
        session = open_session(ZenohOptions(mode="client", connect=[router]))
        probe = make_probe(session, launcher.ns)
        yield probe
    finally:
        if probe is not None:
            probe.close()
        if session is not None:
            session.close()
        launcher.stop()
