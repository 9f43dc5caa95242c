"""Plots of ``bench.fleet``'s results: the cost per drone against the number of drones.

:func:`plot` draws one run (``bench/results/fleet*.png``, written by ``bench.fleet``).
``python -m bench.fleet_plot`` draws the docs' figure, ``docs/fleet_cost.png``, from the
results of two runs of ``bench.fleet`` with the same ``--per-process`` (default 10), one
idle and one with ``--busy``: per drone, the CPU of its sim and bridge and the memory, and
the worst drone's pose age p99, each against N.

    python -m bench.fleet_plot [--per-process 10] [--out docs/fleet_cost.png]
"""

from __future__ import annotations

import json
from pathlib import Path

from bench.common import RESULTS
from dronewrapper.runtime.arguments import CommandParser, first_line

DRONE_ROLES = ("sim", "bridge", "drone (sim+bridge)")
BRIDGE_SHARE_PER_DRONE = 2.0
MEMORY_PER_DRONE_MB = 80.0
POSE_AGE_P99_MS = 50.0
REPO = Path(__file__).resolve().parents[1]


def per_drone(result: dict[str, object], table: str) -> float:
    """A drone's share (sim and bridge, without the router) of ``cpu_percent`` or ``rss_mb``."""
    return sum(result[table].get(role, 0.0) for role in DRONE_ROLES) / result["drones"]


def _pyplot():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def plot(results: list[dict[str, object]], path: Path, title: str) -> None:
    """One run: CPU per drone by role, and memory per drone, against N."""
    plt = _pyplot()
    ok = [r for r in results if "error" not in r]
    counts = [r["drones"] for r in ok]
    fig, (cpu, mem) = plt.subplots(1, 2, figsize=(9, 3.6))
    roles = [role for role in (*DRONE_ROLES, "router") if any(role in r["cpu_percent"] for r in ok)]
    for role in roles:
        cpu.plot(counts, [r["cpu_percent"].get(role, 0) / r["drones"] for r in ok], "o-",
                 label=role)  # fmt: skip
    cpu.axhline(BRIDGE_SHARE_PER_DRONE, color="grey", ls="--", label="bridge target")
    cpu.set_xlabel("drones (N)")
    cpu.set_ylabel("CPU per drone (% of one core)")
    cpu.legend(fontsize=8)
    mem.plot(counts, [per_drone(r, "rss_mb") for r in ok], "o-", label="sim + bridge")
    mem.axhline(MEMORY_PER_DRONE_MB, color="grey", ls="--", label="target")
    mem.set_xlabel("drones (N)")
    mem.set_ylabel("memory per drone (MB RSS)")
    mem.set_ylim(bottom=0)
    mem.legend(fontsize=8)
    for ax in (cpu, mem):
        ax.grid(alpha=0.3)
    fig.suptitle(title, fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=80)
    print(f"wrote {path}")


def plot_docs(runs: dict[str, list[dict[str, object]]], path: Path, title: str) -> None:
    """The docs' figure: for each run (label -> its results), CPU and memory per drone and the
    worst pose age p99 against N."""
    plt = _pyplot()
    fig, (cpu, mem, age) = plt.subplots(1, 3, figsize=(12, 3.6))
    for label, results in runs.items():
        ok = [r for r in results if "error" not in r]
        counts = [r["drones"] for r in ok]
        cpu.plot(counts, [per_drone(r, "cpu_percent") for r in ok], "o-", label=label)
        mem.plot(counts, [per_drone(r, "rss_mb") for r in ok], "o-", label=label)
        age.plot(counts, [r["pose_age_worst_p99_ms"] for r in ok], "o-", label=label)
    cpu.set_ylabel("sim + bridge CPU per drone (% of a core)")
    cpu.set_ylim(bottom=0)
    mem.axhline(MEMORY_PER_DRONE_MB, color="grey", ls="--", label="target")
    mem.set_ylabel("sim + bridge memory per drone (MB RSS)")
    mem.set_yscale("log")
    age.axhline(POSE_AGE_P99_MS, color="grey", ls="--", label="target")
    age.set_ylabel("worst drone's pose age p99 (ms)")
    age.set_yscale("log")
    for ax in (cpu, mem, age):
        ax.set_xlabel("drones (N)")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8)
    fig.suptitle(title, fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=80)
    print(f"wrote {path}")


def main(argv: list[str] | None = None) -> int:
    parser = CommandParser(description=first_line(__doc__))
    parser.add_argument("--per-process", type=int, default=10, help="the runs' --per-process")
    parser.add_argument("--out", type=Path, default=REPO / "docs" / "fleet_cost.png")
    args = parser.parse_args(argv)
    name = "fleet" + (f"_pp{args.per_process}" if args.per_process > 1 else "")
    runs, loads = {}, []
    for suffix, label in (("", "idle"), ("_busy", "one core busy")):
        data = json.loads((RESULTS / f"{name}{suffix}.json").read_text())
        runs[label] = data["results"]
        loads += [r["loadavg"] for r in data["results"] if "loadavg" in r]
    arrangement = "a process each" if args.per_process == 1 else f"{args.per_process} a process"
    title = (f"N simulated Iris ({arrangement}, no cameras) on a shared 2-core machine, "
             f"load {min(loads):.0f}-{max(loads):.0f}: cost per drone against N")  # fmt: skip
    plot_docs(runs, args.out, title)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
