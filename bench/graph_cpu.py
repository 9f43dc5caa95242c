"""CPU use of each whole process graph on this machine (per process and in total).

Runs each graph through the launcher on a free loopback router and free UDP ports, waits for
``--settle`` seconds (take-off), then measures every process's CPU time (``/proc/PID/stat``
utime + stime) over ``--seconds``. 100 % = one core fully busy.
Run: ``python -m bench.graph_cpu [--seconds 20]``; writes bench/results/graph_cpu.json.
"""

from __future__ import annotations

import os
import sys
import time
from pathlib import Path

from bench import common
from bench.common import print_table, write_results
from dronewrapper.runtime.arguments import CommandParser, first_line
from dronewrapper_compose.ports import free_port, private_links

REPO = Path(__file__).resolve().parents[1]
GRAPHS = [
    ("sim_iris", "empty", {}),
    ("sim_follow_color", "beacon_smooth", {}),
    ("sim_follow_person", "people_crossing_front", {"detect_rate_hz": "0"}),
    ("sim_follow_person", "people_crossing_front", {"detect_rate_hz": "10"}),
]
"""(graph, scenario, graph variables): the person app detecting on every frame it can, then
at its default of 10 detections a second."""


def cpu_seconds(pid: int) -> float:
    """User + system CPU seconds of a process so far (0 when it is gone)."""
    try:
        return common.cpu_seconds(pid)
    except OSError:
        return 0.0


def measure(
    graph: str,
    scenario: str,
    seconds: float,
    settle: float,
    extra: dict[str, str] | None = None,
) -> dict[str, float]:
    from dronewrapper_compose.launcher import Launcher

    variables = {
        "scenario": scenario,
        **private_links(),
        "on_exit": "stop",
        **(extra or {}),
    }
    log_path = REPO / "out" / "bench" / f"graph_cpu_{graph}.log"
    log_path.parent.mkdir(parents=True, exist_ok=True)
    with open(log_path, "w") as log_file:
        launcher = Launcher.from_file(
            REPO / "compose" / f"{graph}.yaml",
            router=f"tcp/127.0.0.1:{free_port()}",
            variables=variables,
            out=log_file,
        )
        try:
            launcher.start()
            time.sleep(settle)
            me = os.getpid()
            pids = {c.name: c.proc.pid for c in launcher.children}
            start = {n: cpu_seconds(p) for n, p in pids.items()}
            start_router = cpu_seconds(me)
            t0 = time.monotonic()
            time.sleep(seconds)
            elapsed = time.monotonic() - t0
            usage = {n: 100 * (cpu_seconds(p) - start[n]) / elapsed for n, p in pids.items()}
            usage["router (launcher)"] = 100 * (cpu_seconds(me) - start_router) / elapsed
        finally:
            launcher.stop()
    return usage


def main(argv: list[str] | None = None) -> int:
    parser = CommandParser(description=first_line(__doc__))
    parser.add_argument("--seconds", type=float, default=20.0, help="measuring window (s)")
    parser.add_argument("--settle", type=float, default=15.0, help="wait after start (s)")
    args = parser.parse_args(argv)
    results, rows = {}, []
    for graph, scenario, extra in GRAPHS:
        usage = measure(graph, scenario, args.seconds, args.settle, extra)
        total = sum(usage.values())
        settings = " ".join(f"{k}={v}" for k, v in extra.items())
        name = f"{graph} {settings}".strip()
        results[name] = {"scenario": scenario, "cpu_percent": usage, "total_percent": total}
        detail = ", ".join(f"{n} {v:.0f}" for n, v in usage.items())
        rows.append([name, scenario, total, detail])
    print_table(
        f"CPU of each graph (% of one core; this machine has {os.cpu_count()} cores)",
        ["graph", "scenario", "total %", "per process %"],
        rows,
    )
    write_results("graph_cpu", {"seconds": args.seconds, "graphs": results})
    return 0


if __name__ == "__main__":
    sys.exit(main())
