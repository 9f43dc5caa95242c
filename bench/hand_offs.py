"""The hand-offs of a round trip: context switches and CPU migrations of a process's
threads, read from ``/proc/PID/task/*`` (Linux), counted around a timed loop of round trips."""

from __future__ import annotations

import os
import time

import numpy as np

from bench.common import cpu_seconds


def thread_switches(pid: int) -> dict[str, int]:
    """Voluntary + involuntary context switches so far of each thread of ``pid`` by name
    (threads of one name summed)."""
    counts: dict[str, int] = {}
    for task in os.listdir(f"/proc/{pid}/task"):
        try:
            with open(f"/proc/{pid}/task/{task}/comm") as comm:
                name = comm.read().strip()
            with open(f"/proc/{pid}/task/{task}/status") as status:
                total = sum(int(line.split()[-1]) for line in status if "ctxt_switches:" in line)
        except (FileNotFoundError, ProcessLookupError):
            continue  # a thread that ended meanwhile
        counts[name] = counts.get(name, 0) + total
    return counts


def migrations(pid: int) -> int:
    """Moves of ``pid``'s threads from one CPU to another so far (``se.nr_migrations``)."""
    total = 0
    for task in os.listdir(f"/proc/{pid}/task"):
        try:
            with open(f"/proc/{pid}/task/{task}/sched") as sched:
                total += sum(int(line.split()[-1]) for line in sched if "nr_migrations" in line)
        except (FileNotFoundError, ProcessLookupError):
            continue  # a thread that ended meanwhile
    return total


def measure(send, wait, samples: int, pids: dict[str, int], warmup: int = 100):
    """Round trips (s) of ``send()`` then ``wait()``, the context switches per round trip of
    each thread of the processes ``pids`` (``"role/thread name"``: count) and their CPU time
    per round trip (``"cpu_us"``, microseconds, in clock ticks' resolution)."""
    for _ in range(warmup):
        send()
        wait()
    before = {role: thread_switches(pid) for role, pid in pids.items()}
    cpu_before = sum(cpu_seconds(pid) for pid in pids.values())
    moves_before = sum(migrations(pid) for pid in pids.values())
    rtts = np.empty(samples)
    for i in range(samples):
        t0 = time.perf_counter()
        send()
        wait()
        rtts[i] = time.perf_counter() - t0
    cpu_us = (sum(cpu_seconds(pid) for pid in pids.values()) - cpu_before) / samples * 1e6
    moves = (sum(migrations(pid) for pid in pids.values()) - moves_before) / samples
    per_rtt = {}
    for role, pid in pids.items():
        for name, count in thread_switches(pid).items():
            per_rtt[f"{role}/{name}"] = (count - before[role].get(name, 0)) / samples
    return rtts, per_rtt, cpu_us, moves
