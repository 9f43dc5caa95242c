"""Where a Zenoh link stalls, from ``/proc``: every ``--period`` s, one JSON line with the TCP
queues of the connections on a port and, for each thread of the processes at either end that
match ``--watch`` (and of the process listening on the port: the router), its state, wait
channel, CPU time and run-queue wait.

Run beside a flight in the same network namespace (``/proc/net/tcp`` is the namespace's), as
root to read other processes' wait channels. A line::

    {"t": unix s, "cpu": the first line of /proc/stat (user nice system idle iowait irq
     softirq steal, ticks), "socks": [[local port, remote port, state (hex), bytes queued to
     send, bytes queued unread, pid, command]], "thr": {pid: {tid: [name, state, wait channel,
     cpu ns, run-queue wait ns, policy, real-time priority]}}}

Read beside the router's view and PX4's uORB echo (tests/sitl/px4_zenoh_sitl.py), it tells a
router that wrote nothing to PX4 (no byte queued at its end, zenoh-pico's read task idle in
``recv``) from a reader that did not read (bytes waiting unread at PX4's end) and from a
starved process (its runnable threads' run-queue wait), as docs/px4_zenoh.md reports.

    python -m bench.link_sampler OUT.jsonl [--port 7447] [--period 0.05] [--watch px4]
"""

from __future__ import annotations

import json
import os
import time
from pathlib import Path
from typing import Any

from dronewrapper.runtime.arguments import CommandParser, first_line

LISTEN = "0A"  # TCP state LISTEN in /proc/net/tcp


def tcp_rows(port: int, table: str = "/proc/net/tcp") -> list[tuple[int, int, str, int, int, str]]:
    """(local port, remote port, state, send queue, unread queue, inode) of the connections
    with ``port`` at either end."""
    rows = []
    with open(table) as f:
        next(f)
        for line in f:
            p = line.split()
            local, remote = int(p[1].split(":")[1], 16), int(p[2].split(":")[1], 16)
            if port in (local, remote):
                tx, rx = p[4].split(":")
                rows.append((local, remote, p[3], int(tx, 16), int(rx, 16), p[9]))
    return rows


def socket_owners() -> dict[str, int]:
    """Socket inode -> the pid holding it."""
    owners = {}
    for pid in filter(str.isdigit, os.listdir("/proc")):
        try:
            for fd in os.listdir(f"/proc/{pid}/fd"):
                target = os.readlink(f"/proc/{pid}/fd/{fd}")
                if target.startswith("socket:["):
                    owners[target[8:-1]] = int(pid)
        except OSError:
            continue
    return owners


def command(pid: int) -> str:
    try:
        return Path(f"/proc/{pid}/comm").read_text().strip()
    except OSError:
        return "?"


def threads(pid: int) -> dict[str, list[Any]]:
    """Each thread's [name, state, wait channel, cpu ns, run-queue wait ns, policy, rt prio]."""
    out: dict[str, list[Any]] = {}
    try:
        tids = os.listdir(f"/proc/{pid}/task")
    except OSError:
        return out
    for tid in tids:
        base = f"/proc/{pid}/task/{tid}/"
        try:
            stat = Path(base + "stat").read_text()
            fields = stat[stat.rindex(")") + 2 :].split()
            name = stat[stat.index("(") + 1 : stat.rindex(")")]
            on_cpu, waiting = Path(base + "schedstat").read_text().split()[:2]
            wchan = Path(base + "wchan").read_text().strip()
        except OSError:
            continue
        out[tid] = [
            name,
            fields[0],
            wchan,
            int(on_cpu),
            int(waiting),
            int(fields[38]),
            int(fields[37]),
        ]
    return out


def sample(port: int, watch: str, owners: dict[str, int]) -> dict[str, Any]:
    """One line's record."""
    socks, watched = [], set()
    for local, remote, state, tx, rx, inode in tcp_rows(port):
        pid = owners.get(inode)
        name = command(pid) if pid else "?"
        socks.append([local, remote, state, tx, rx, pid, name])
        if pid and (name.startswith(watch) or (local == port and state == LISTEN)):
            watched.add(pid)
    with open("/proc/stat") as f:
        cpu = f.readline().split()[1:9]
    return {"t": time.time(), "cpu": cpu, "socks": socks, "thr": {p: threads(p) for p in watched}}


def main(argv: list[str] | None = None) -> int:
    parser = CommandParser(description=first_line(__doc__))
    parser.add_argument("out", type=Path, help="the JSON lines file")
    parser.add_argument("--port", type=int, default=7447, help="the router's TCP port")
    parser.add_argument("--period", type=float, default=0.05, help="s between samples")
    parser.add_argument("--watch", default="px4", help="command prefix of the processes watched")
    args = parser.parse_args(argv)
    owners, mapped = socket_owners(), time.monotonic()
    with args.out.open("w") as out:
        while True:
            began = time.monotonic()
            if began - mapped > 2.0:  # new connections: whose are they
                owners, mapped = socket_owners(), began
            out.write(json.dumps(sample(args.port, args.watch, owners)) + "\n")
            out.flush()
            time.sleep(max(0.0, args.period - (time.monotonic() - began)))


if __name__ == "__main__":
    raise SystemExit(main())
