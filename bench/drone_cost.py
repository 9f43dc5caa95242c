"""What one simulated drone (sim + bridge) costs in CPU, at N drones on one router.

For each N it starts ``compose/sim_fleet`` (N Iris without cameras, ``--per-process``
drones a process; ``dronewrapper up`` holds the router) and, once every drone is ready and
``--settle`` s have passed, measures over ``--seconds``: the CPU seconds (user + system, from
``/proc``) that the fleet's processes spent per drone per second of wall time, in % of one
core; with ``--per-process 1``, the sims' and the bridges' apart. With ``--subscribe`` one
subscriber (``bench.pose_ages``, a process of its own) takes every drone's pose meanwhile, as
an application does, and gives their ages and rates; without, nobody reads the bridges'
samples. CPU time is counted, not wall time, so the figures depend less on
what else runs on the machine than a latency does (a loaded machine still costs more per unit
of work: caches, frequency).

With ``--split`` it runs no graph but two host processes on a router of its own (N > 1):
the N sims in one, the N bridges in the other, each drone's sim and bridge as the graph makes
them, so a bridge's CPU in a shared process is measured apart from its sim's.

``--busy`` keeps one core busy with an unrelated program meanwhile (as ``bench.fleet``).

With ``--threads`` it also splits the fleet's CPU by thread: Zenoh's own threads (named by
Rust: ``rx-0``, ``tx-0``, ``net-0`` ...) against the interpreter's (``python``).

    nice -n 10 python -m bench.drone_cost [--counts 1 10 30] [--per-process 10]
        [--seconds 10] [--subscribe] [--threads] [--split] [--busy]
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import time
from collections import defaultdict
from collections.abc import Iterable
from pathlib import Path
from typing import Any

from bench.busy import busy_core
from bench.common import CLK_TCK, free_endpoint, print_table, stop_process, write_results
from dronewrapper.runtime.arguments import CommandParser, first_line

REPO = Path(__file__).resolve().parents[1]


def thread_cpu(pid: int) -> dict[str, float]:
    """CPU seconds so far of each thread name of process ``pid`` (summed over threads of one
    name; a trailing number is dropped: ``rx-3`` counts as ``rx``)."""
    out: dict[str, float] = defaultdict(float)
    for task in Path(f"/proc/{pid}/task").glob("*"):
        try:
            head, tail = (task / "stat").read_text().rsplit(")", 1)
        except OSError:
            continue
        name = head.split("(", 1)[1].rstrip("0123456789").rstrip("-")
        fields = tail.split()
        out[name] += (int(fields[11]) + int(fields[12])) / CLK_TCK
    return out


def fleet_processes(launcher: int) -> dict[int, str]:
    """{pid: role} of the launcher's children: ``sim``, ``bridge`` or ``host``."""
    found = {}
    for stat in Path("/proc").glob("[0-9]*/stat"):
        try:
            ppid = int(stat.read_text().rsplit(")", 1)[1].split()[1])
            cmdline = (stat.parent / "cmdline").read_bytes().decode().split("\0")
        except (OSError, ValueError):
            continue
        if ppid != launcher or "-m" not in cmdline:
            continue
        module = cmdline[cmdline.index("-m") + 1]
        found[int(stat.parent.name)] = {
            "dronewrapper_sim": "sim",
            "dronewrapper.runtime.host": "host",
        }.get(module, "bridge")
    return found


class Poses:
    """The pose subscriber ``bench.pose_ages`` (a process of its own) on ``endpoint``."""

    def __init__(self, endpoint: str) -> None:
        self.child = subprocess.Popen(
            [sys.executable, "-m", "bench.pose_ages", endpoint],
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            text=True,
            cwd=REPO,
        )
        self.child.stdout.readline()  # "ready"

    def command(self, line: str) -> dict[str, object]:
        self.child.stdin.write(line + "\n")
        self.child.stdin.flush()
        return json.loads(self.child.stdout.readline()) if line == "stop" else {}

    def close(self) -> None:
        self.child.stdin.close()
        self.child.wait(10)


def pose_figures(report: dict[str, object] | None) -> dict[str, object]:
    """Poses a second in all, worst drone's age p99 (ms), slowest drone's rate (Hz)."""
    if report is None:
        return {"poses_per_s": None}
    per_drone, rates = report["per_drone"], report["rate_hz"]
    return {
        "poses_per_s": sum(rates.values()),
        "pose_age_p50_ms": report["all"].get("p50_ms"),
        "pose_age_worst_p99_ms": max((p.get("p99_ms", 0.0) for p in per_drone.values()), default=0),
        "pose_rate_min_hz": min(rates.values(), default=0.0),
    }


def split_hosts(
    n: int, endpoint: str, loop_hz: str = "30", physics_hz: str = "100"
) -> list[subprocess.Popen]:
    """Two host processes on ``endpoint``: N sims in the first, their N bridges in the other
    (the sims as ``compose/sim_fleet.yaml`` makes them)."""
    from dronewrapper_compose.ports import free_port

    sims: list[str] = []
    bridges: list[str] = []
    for i in range(1, n + 1):
        port = free_port("udp")
        bus = ["--connect", endpoint, "--namespace", f"drone{i}", "--mode", "peer",
               "--log-level", "WARNING"]  # fmt: skip
        sims += ["-m", "dronewrapper_sim", "--scenario", "empty", "--udp-onboard", f"{port}:0",
                 "--udp-gcs", "off", "--set", "cameras=false", "--set",
                 f"loop_rate_hz={loop_hz}", "--set", f"physics_rate_hz={physics_hz}",
                 "--name", "sim", *bus, "--"]  # fmt: skip
        bridges += ["-m", "dronewrapper_bridge_mavlink", "--set",
                    f"connection=udpin:127.0.0.1:{port}", "--name", "bridge_mavlink", *bus,
                    "--"]  # fmt: skip
    host = [sys.executable, "-m", "dronewrapper.runtime.host"]
    return [subprocess.Popen([*host, *members[:-1]], cwd=REPO) for members in (sims, bridges)]


def cpu_window(
    pids: Iterable[int], poses: Poses | None, seconds: float
) -> tuple[dict[int, dict[str, float]], dict[int, dict[str, float]], float, Any]:
    """Each process's CPU per thread (s) before and after ``seconds`` of wall time, the pose
    subscriber (if any) counting in between: (before, after, elapsed s, its report)."""
    before = {pid: thread_cpu(pid) for pid in pids}
    if poses is not None:
        poses.command("start")
    t0 = time.monotonic()
    time.sleep(seconds)
    elapsed = time.monotonic() - t0
    report = poses.command("stop") if poses is not None else None
    after = {pid: thread_cpu(pid) for pid in pids}
    return before, after, elapsed, report


def measure_split(n: int, seconds: float, settle: float, subscribe: bool) -> dict[str, object]:
    """N sims in one host, N bridges in another: each one's CPU per drone."""
    from bench.common import LoopbackRouter

    router = LoopbackRouter()
    router.start()
    sims, bridges = split_hosts(n, router.endpoint)
    poses = None
    try:
        if subscribe:
            poses = Poses(router.endpoint)
        time.sleep(settle + 0.3 * n)  # the members start one after another
        before, after, elapsed, report = cpu_window([sims.pid, bridges.pid], poses, seconds)
        per = {}
        for role, proc in (("sims' host", sims), ("bridges' host", bridges)):
            spent = sum(after[proc.pid].values()) - sum(before[proc.pid].values())
            per[role] = 100 * spent / elapsed / n
        return {
            "drones": n,
            "per_process": n,
            "split": True,
            "cpu_percent_per_drone": per,
            "total_percent_per_drone": sum(per.values()),
            "threads_percent_per_drone": {},
            **pose_figures(report),
            "loadavg": os.getloadavg()[0],
        }
    finally:
        if poses is not None:
            poses.close()
        for proc in (bridges, sims):
            stop_process(proc, timeout_s=30)
        router.stop()


def measure(
    n: int, per_process: int, seconds: float, settle: float, subscribe: bool
) -> dict[str, object]:
    """Start N drones, measure their CPU over ``seconds``, stop them."""
    endpoint = free_endpoint()
    log_path = REPO / "out" / "bench" / f"drone_cost_{n}.log"
    log_path.parent.mkdir(parents=True, exist_ok=True)
    argv = [sys.executable, "-m", "dronewrapper", "up", "sim_fleet", "--router", endpoint,
            "--var", f"drones={n}", "--var", f"per_process={min(per_process, n)}"]  # fmt: skip
    with open(log_path, "w") as log:
        up = subprocess.Popen(argv, stdout=log, stderr=subprocess.STDOUT, cwd=REPO)
    poses = None
    out: dict[str, object] = {"drones": n, "per_process": min(per_process, n)}
    try:
        started = time.monotonic()
        while "all processes ready" not in log_path.read_text():
            if up.poll() is not None or time.monotonic() - started > 60 + 5 * n:
                out["error"] = f"the fleet did not start (see {log_path})"
                return out
            time.sleep(0.2)
        if subscribe:
            poses = Poses(endpoint)
        time.sleep(settle)
        pids = fleet_processes(up.pid)
        before, after, elapsed, report = cpu_window(pids, poses, seconds)
        roles: dict[str, float] = defaultdict(float)
        by_thread: dict[str, float] = defaultdict(float)
        for pid, role in pids.items():
            for name, cpu in after[pid].items():
                spent = cpu - before[pid].get(name, 0.0)
                roles[role] += spent
                by_thread[name] += spent
        per = {role: 100 * cpu / elapsed / n for role, cpu in roles.items()}
        out.update(
            cpu_percent_per_drone=per,
            total_percent_per_drone=sum(per.values()),
            threads_percent_per_drone={k: 100 * v / elapsed / n for k, v in by_thread.items()},
            **pose_figures(report),
            loadavg=os.getloadavg()[0],
        )
        return out
    finally:
        if poses is not None:
            poses.close()
        stop_process(up, timeout_s=60 + n)


def main(argv: list[str] | None = None) -> int:
    parser = CommandParser(description=first_line(__doc__))
    parser.add_argument("--counts", type=int, nargs="+", default=[1, 10, 30])
    parser.add_argument("--per-process", type=int, default=10, help="drones per process")
    parser.add_argument("--seconds", type=float, default=10.0, help="measuring window (s)")
    parser.add_argument("--settle", type=float, default=5.0, help="wait after start (s)")
    parser.add_argument("--subscribe", action="store_true", help="subscribe to every pose")
    parser.add_argument("--threads", action="store_true", help="split the CPU by thread")
    parser.add_argument("--split", action="store_true", help="sims and bridges apart")
    parser.add_argument("--busy", action="store_true", help="keep one core busy meanwhile")
    args = parser.parse_args(argv)
    results = []
    with busy_core(args.busy):
        for n in args.counts:
            print(f"... {n} drone(s)", flush=True)
            if args.split:
                result = measure_split(n, args.seconds, args.settle, args.subscribe)
            else:
                result = measure(n, args.per_process, args.seconds, args.settle, args.subscribe)
            results.append({**result, "busy_core": args.busy})
    report(results, args.threads)
    name = "drone_cost" + ("_split" if args.split else "") + ("_busy" if args.busy else "")
    write_results(name, {"results": results})
    return 0


def report(results: list[dict[str, object]], threads: bool) -> None:
    rows = []
    for r in results:
        if "error" in r:
            rows.append([r["drones"], r["error"], "", "", "", "", ""])
            continue
        per = r["cpu_percent_per_drone"]
        split = ", ".join(f"{k} {v:.2f}" for k, v in sorted(per.items()))
        ages = "-"
        if r["poses_per_s"] is not None:
            ages = f"{r['pose_age_p50_ms']:.1f} / {r['pose_age_worst_p99_ms']:.0f}"
        rows.append([r["drones"], r["total_percent_per_drone"], split,
                     r["poses_per_s"] if r["poses_per_s"] is not None else "-",
                     r.get("pose_rate_min_hz", "-"), ages, r["loadavg"]])  # fmt: skip
    print_table(
        "CPU per drone (% of one core: sim + bridge, the router not counted)",
        ["N", "per drone", "by process", "poses/s", "slowest Hz", "age p50 / worst p99 ms",
         "load"],
        rows,
    )  # fmt: skip
    if threads:
        for r in results:
            if "error" not in r and r["threads_percent_per_drone"]:
                top = sorted(r["threads_percent_per_drone"].items(), key=lambda kv: -kv[1])
                print(f"  N={r['drones']} by thread: "
                      + ", ".join(f"{k} {v:.2f}" for k, v in top[:8]))  # fmt: skip


if __name__ == "__main__":
    raise SystemExit(main())
