"""Where a 64-byte round trip's time goes: the same ping/echo over plain zenoh-python, one
variant changed at a time, with the thread hand-offs counted.

Each variant is two fresh processes on loopback, a ping and an echo, peer to peer unless it
says router. What a variant changes:

* how the ping side waits for its pong: an ``Event`` set by a subscriber callback run on a
  Python thread of the binding's (``indirect``, the binding's default), or run directly on
  Zenoh's receive thread (``direct``; ``kept``: and that thread keeps its Python thread state,
  see ``dronewrapper.runtime.thread_state``), or the main thread blocked in a FIFO channel's
  ``recv()`` (``recv``: no callback at all);
* how the echo answers: the same three (``recv`` = a Python thread blocked in ``recv()``);
* how it publishes: a declared publisher, an ``express`` one (no batching), ``session.put``;
* Zenoh configuration on every session of the variant (``lowlatency`` transport, QoS off,
  batching off, priority) and Zenoh's receive runtime on one thread (``ZENOH_RUNTIME``);
* ``ours``: our runtime's Node on both ends (or on one), a typed 64-byte CompressedImage
  encoded and decoded, the ways ``ZenohOptions`` and ``Node`` offer.

Besides the round trip's p50/p99 it reports the context switches of both processes per round
trip (``/proc/PID/task/*/status``, voluntary + involuntary): each is a thread going to sleep
and being woken, so it counts the hand-offs whatever the load; and their threads' moves from
one CPU to another (``se.nr_migrations`` in ``/proc/PID/task/*/sched``): a thread woken on
the other CPU, which on a virtual machine may have to be woken from its halt first. Rounds
are interleaved (every variant once per round) and the table gives the median of the rounds'
p50, so a burst of load from other processes hits every variant alike. ``socket`` is a plain
Python TCP echo built the way rospy's TCPROS is (a reader thread per connection, an ``Event``
to the caller): the floor of that design in this Python. ``--placement`` pins the two
processes: ``same`` (both on CPU 0), ``split`` (CPU 0 and CPU 1).

    python -m bench.transport_breakdown [--samples 1000] [--rounds 3] [--only NAME ...]
                                        [--placement any|same|split] [--threads]
"""

from __future__ import annotations

import argparse
import contextlib
import json
import os
import socket
import struct
import subprocess
import sys
import threading
import time
from collections.abc import Callable
from dataclasses import asdict

import numpy as np
import zenoh

from bench.breakdown_echo import serve_echo, serve_socket
from bench.breakdown_variants import (
    PAYLOAD,
    PING_KEY,
    PONG_KEY,
    SOCKET,
    VARIANTS,
    Variant,
    node_for,
    publisher,
    qos,
    session_config,
    small_message,
    subscribe,
)
from bench.common import free_endpoint, print_table, write_results
from bench.hand_offs import measure
from dronewrapper.msgs import registry
from dronewrapper.runtime.arguments import CommandParser, first_line

# ---- the measuring process ----


class Child:
    """A child process of this module (an echo, a ping); its first line of output is kept."""

    def __init__(
        self, args: list[str], env: dict[str, str] | None = None, cpus: set[int] | None = None
    ) -> None:
        command = [sys.executable, "-m", "bench.transport_breakdown", *args]
        pin = (lambda: os.sched_setaffinity(0, cpus)) if cpus else None
        self.proc = subprocess.Popen(
            command, stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True, env=env,
            preexec_fn=pin,
        )  # fmt: skip
        self.first_line = self.proc.stdout.readline().strip()

    def close(self) -> None:
        self.proc.stdin.close()
        try:
            self.proc.wait(10)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            self.proc.wait(5)


def serve_ping(variant: Variant, mode: str, connect: list[str], samples: int, echo_pid: int):
    """In the second child: measure the round trips against the echo, print them as JSON."""
    if variant.layer in ("ours", "ours_ping"):
        return serve_ping_ours(variant, mode, connect, samples, echo_pid)
    session = zenoh.open(session_config(variant, mode, connect, []))
    try:
        got = threading.Event()
        put = publisher(session, PING_KEY, variant)
        sub = subscribe(session, PONG_KEY, variant.ping, lambda _payload: got.set())
        if variant.ping == "recv":
            watchdog = threading.Timer(120.0, session.close)  # a lost pong ends recv()
            watchdog.daemon = True
            watchdog.start()

            def wait() -> None:
                sub.recv().payload.to_bytes()

        else:
            wait = pong_wait(got, variant.name)

        time.sleep(0.5)  # let the routes settle
        pids = {"ping": os.getpid(), "echo": echo_pid}
        rtts, per_rtt, cpu_us, moves = measure(lambda: put(PAYLOAD), wait, samples, pids)
        if variant.ping == "recv":
            watchdog.cancel()
        print_figures(rtts, per_rtt, cpu_us, moves)
    finally:
        session.close()


def pong_wait(got: threading.Event, name: str) -> Callable[[], None]:
    """A wait for the next pong that ``got`` signals (RuntimeError after 2 s)."""

    def wait() -> None:
        if not got.wait(2.0):
            raise RuntimeError(f"{name}: no pong within 2 s")
        got.clear()

    return wait


def print_figures(rtts, per_rtt, cpu_us, moves) -> None:
    """One ping process's figures: a JSON line on stdout, read by the parent."""
    print(
        json.dumps(
            {"rtts": rtts.tolist(), "switches": per_rtt, "cpu_us": cpu_us, "migrations": moves}
        ),
        flush=True,
    )


def serve_ping_ours(variant: Variant, mode: str, connect: list[str], samples: int, echo_pid: int):
    """``serve_ping`` through our runtime: a typed publisher, a decoding subscriber."""
    with node_for(variant, "ping", mode, connect, []) as node:
        got = threading.Event()
        pub = node.publisher(registry.IMAGE_COMPRESSED, key=PING_KEY, qos=qos(variant))
        node.subscribe(registry.IMAGE_COMPRESSED, lambda _msg: got.set(), key=PONG_KEY)
        wait = pong_wait(got, variant.name)
        time.sleep(0.5)  # let the routes settle
        pids = {"ping": os.getpid(), "echo": echo_pid}
        rtts, per_rtt, cpu_us, moves = measure(
            lambda: pub.put(small_message()), wait, samples, pids
        )
        print_figures(rtts, per_rtt, cpu_us, moves)


PLACEMENTS = {"any": {}, "same": {"ping": {0}, "echo": {0}}, "split": {"ping": {0}, "echo": {1}}}
"""Where the two processes may run: anywhere (the scheduler decides, run by run), both on
CPU 0 (every hand-off stays on one CPU), or one on each CPU (every message crosses)."""


def run_zenoh(variant: Variant, samples: int, placement: str = "any"):
    """One measurement of ``variant`` (an echo process and a ping process, both fresh, so
    that ``variant.env`` reaches Zenoh's runtime): round trips (s) and context switches per
    round trip by thread."""
    router = None
    endpoint = free_endpoint()
    if variant.router:
        router = zenoh.open(session_config(variant, "router", [], [endpoint]))
        mode, echo_args = "client", ["--connect", endpoint]
    else:
        mode, echo_args = "peer", ["--listen", endpoint]
    spec = json.dumps(asdict(variant))
    env = {**os.environ, **variant.env}
    cpus = PLACEMENTS[placement]
    echo = Child(["--echo", spec, "--mode", mode, *echo_args], env, cpus.get("echo"))
    try:
        if echo.first_line != "ready":
            raise RuntimeError(f"{variant.name}: the echo did not start")
        ping_args = ["--ping", spec, "--mode", mode, "--connect", endpoint,
                     "--samples", str(samples), "--echo-pid", str(echo.proc.pid)]  # fmt: skip
        ping = Child(ping_args, env, cpus.get("ping"))
        ping.close()
        if not ping.first_line.startswith("{"):
            raise RuntimeError(f"{variant.name}: the ping failed")
        result = json.loads(ping.first_line)
        switches = result["switches"]
        if router is not None:
            switches.update({f"router/{t}": n for t, n in result.get("router", {}).items()})
        return np.asarray(result["rtts"]), switches, result["cpu_us"], result["migrations"]
    finally:
        echo.close()
        if router is not None:
            router.close()


def run_socket(samples: int, placement: str = "any"):
    """One measurement of the plain socket echo (rospy's design; this process pings)."""
    cpus = PLACEMENTS[placement]
    mine = os.sched_getaffinity(0)
    os.sched_setaffinity(0, cpus.get("ping", mine))
    echo = Child(["--socket"], cpus=cpus.get("echo"))
    conn = socket.create_connection(("127.0.0.1", int(echo.first_line)))
    conn.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
    got = threading.Event()

    def loop() -> None:
        with contextlib.suppress(OSError):  # the socket closed: the measurement is over
            while True:
                head = conn.recv(4, socket.MSG_WAITALL)
                if len(head) < 4:
                    return
                conn.recv(struct.unpack("<I", head)[0], socket.MSG_WAITALL)
                got.set()

    reader = threading.Thread(target=loop, daemon=True)
    reader.start()
    frame = struct.pack("<I", len(PAYLOAD)) + PAYLOAD

    def wait() -> None:
        if not got.wait(2.0):
            raise RuntimeError("socket echo: no pong within 2 s")
        got.clear()

    try:
        pids = {"ping": os.getpid(), "echo": echo.proc.pid}
        return measure(lambda: conn.sendall(frame), wait, samples, pids)
    finally:
        conn.shutdown(socket.SHUT_RDWR)
        reader.join(2.0)
        conn.close()
        echo.close()
        os.sched_setaffinity(0, mine)


def main(argv: list[str] | None = None) -> int:
    parser = CommandParser(description=first_line(__doc__))
    parser.add_argument("--samples", type=int, default=1000, help="round trips per round")
    parser.add_argument("--rounds", type=int, default=3, help="interleaved rounds")
    parser.add_argument("--only", action="append", help="variants whose name contains this")
    parser.add_argument("--threads", action="store_true", help="context switches per thread")
    parser.add_argument(
        "--placement", choices=sorted(PLACEMENTS), default="any",
        help="CPUs of the two processes: any, same (both on CPU 0), split (CPU 0 and 1)",
    )  # fmt: skip
    parser.add_argument("--echo", help=argparse.SUPPRESS)
    parser.add_argument("--ping", help=argparse.SUPPRESS)
    parser.add_argument("--echo-pid", type=int, help=argparse.SUPPRESS)
    parser.add_argument("--socket", action="store_true", help=argparse.SUPPRESS)
    parser.add_argument("--mode", default="peer", help=argparse.SUPPRESS)
    parser.add_argument("--connect", action="append", default=[], help=argparse.SUPPRESS)
    parser.add_argument("--listen", action="append", default=[], help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.echo:
        serve_echo(Variant(**json.loads(args.echo)), args.mode, args.connect, args.listen)
        return 0
    if args.ping:
        variant = Variant(**json.loads(args.ping))
        serve_ping(variant, args.mode, args.connect, args.samples, args.echo_pid)
        return 0
    if args.socket:
        serve_socket()
        return 0
    results = run(args.samples, args.rounds, args.only, args.placement)
    report(results, args.threads)
    write_results("transport_breakdown", {"variants": results})
    return 0


def run(
    samples: int, rounds: int, only: list[str] | None = None, placement: str = "any"
) -> dict[str, dict]:
    """Every chosen variant once per round; per variant the rounds' p50s, the pooled p99 and
    the context switches per round trip (median of the rounds)."""
    chosen = [v for v in VARIANTS if not only or any(o in v.name for o in only)]
    with_socket = not only or any(o in SOCKET for o in only)
    names = [v.name for v in chosen] + ([SOCKET] if with_socket else [])
    pooled: dict[str, list[np.ndarray]] = {name: [] for name in names}
    switches: dict[str, list[dict[str, float]]] = {name: [] for name in names}
    cpu: dict[str, list[float]] = {name: [] for name in names}
    moved: dict[str, list[float]] = {name: [] for name in names}
    for _ in range(rounds):
        runs = [(v.name, lambda v=v: run_zenoh(v, samples, placement)) for v in chosen]
        if with_socket:
            runs.append((SOCKET, lambda: run_socket(samples, placement)))
        for name, run_once in runs:
            rtts, per_rtt, cpu_us, moves = run_once()
            moved[name].append(moves)
            pooled[name].append(rtts)
            switches[name].append(per_rtt)
            cpu[name].append(cpu_us)
    results = {}
    for name in names:
        p50s = [float(np.percentile(r, 50)) * 1e3 for r in pooled[name]]
        every = np.concatenate(pooled[name]) * 1e3
        threads = sorted({t for counts in switches[name] for t in counts})
        by_thread = {t: float(np.median([c.get(t, 0.0) for c in switches[name]])) for t in threads}
        results[name] = {
            "p50_ms": float(np.median(p50s)),
            "p50_ms_rounds": p50s,
            "p99_ms": float(np.percentile(every, 99)),
            "switches_per_rtt": float(np.median([sum(c.values()) for c in switches[name]])),
            "switches_per_rtt_by_thread": {t: n for t, n in by_thread.items() if n >= 0.05},
            "cpu_us_per_rtt": float(np.median(cpu[name])),
            "migrations_per_rtt": float(np.median(moved[name])),
        }
    return results


def report(results: dict[str, dict], threads: bool = False) -> None:
    """Print the table, each variant also against the binding's defaults (and with
    ``threads`` which threads were woken per round trip)."""
    base = next(iter(results.values()))["p50_ms"]
    rows = [
        [name, r["p50_ms"], min(r["p50_ms_rounds"]), r["p99_ms"], r["p50_ms"] / base,
         r["switches_per_rtt"], r["migrations_per_rtt"], r["cpu_us_per_rtt"]]
        for name, r in results.items()
    ]  # fmt: skip
    print_table(
        "64-byte round trip between two processes, plain zenoh-python, one change at a time",
        [
            "variant",
            "p50",
            "best p50",
            "p99",
            "vs defaults",
            "switches / RTT",
            "moves / RTT",
            "CPU µs / RTT",
        ],
        rows,
    )
    print(
        "  (ms; p50 = median of the rounds' medians, best = lowest round; p99 over all rounds;\n"
        "   context switches of both processes per round trip: threads woken and put to sleep;\n"
        "   moves: their threads' migrations from one CPU to the other per round trip;\n"
        "   CPU: both processes' user + system time per round trip)"
    )
    if threads:
        for name, r in results.items():
            woken = ", ".join(f"{t} {n:.1f}" for t, n in r["switches_per_rtt_by_thread"].items())
            print(f"  {name}: {woken}")


if __name__ == "__main__":
    raise SystemExit(main())
