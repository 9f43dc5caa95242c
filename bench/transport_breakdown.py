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
from dataclasses import asdict, dataclass, field

import numpy as np
import zenoh

from bench.common import cpu_seconds, free_endpoint, print_table, write_results
from dronewrapper.msgs import CompressedImage, Header, codec, registry
from dronewrapper.runtime import Node
from dronewrapper.runtime.arguments import CommandParser, first_line
from dronewrapper.runtime.options import ZenohOptions, zenoh_config
from dronewrapper.runtime.session import encoding_for
from dronewrapper.runtime.thread_state import KEPT

PING_KEY, PONG_KEY = "bench/breakdown/ping", "bench/breakdown/pong"
DATA = bytes(64)
LOW_LATENCY = {"transport/unicast/lowlatency": "true", "transport/unicast/qos/enabled": "false"}
NO_QOS = {"transport/unicast/qos/enabled": "false"}
NO_BATCHING = {"transport/link/tx/queue/batching/enabled": "false"}
ONE_RX = {"ZENOH_RUNTIME": "(rx: (worker_threads: 1))"}
TWO_RX = {"ZENOH_RUNTIME": "(rx: (worker_threads: 2))"}  # the binding's default
SUMMARY = (
    "binding defaults",
    "direct callbacks both",
    "thread states kept",
    "lowlatency transport",
    "one rx thread",
    "recv ping, direct echo, lowlatency, one rx thread",
    "ours: Node defaults",
    "ours: low_latency",
    "socket",
)
"""The variants ``bench.transport`` prints (names containing one of these)."""


@dataclass(frozen=True)
class Variant:
    """One way of doing the 64-byte round trip (see the module docstring)."""

    name: str
    ping: str = "indirect"
    echo: str = "indirect"
    put: str = "publisher"
    config: dict[str, str] = field(default_factory=dict)
    router: bool = False
    priority: str = "DATA"
    congestion: str = "BLOCK"
    env: dict[str, str] = field(default_factory=dict)
    encoding: bool = False
    """Declare the plain publishers with our encoding (MessagePack and the type's schema)."""
    layer: str = "zenoh"
    """``zenoh``: plain zenoh-python bytes; ``ours``: a Node on each end, a 64-byte
    CompressedImage typed, encoded and decoded (``ping``/``echo``: ``indirect`` or ``direct``
    callbacks; ``config`` LOW_LATENCY becomes ``ZenohOptions.low_latency``); ``ours_ping``,
    ``ours_echo``: a Node on that end only."""


VARIANTS = (
    Variant("binding defaults (callbacks on Python threads)"),
    Variant("express publisher", put="express"),
    Variant("session.put", put="session"),
    Variant("with our encoding (schema)", encoding=True),
    Variant("congestion DROP", congestion="DROP"),
    Variant("priority INTERACTIVE_HIGH", priority="INTERACTIVE_HIGH"),
    Variant("QoS off", config=NO_QOS),
    Variant("batching off", config=NO_BATCHING),
    Variant("lowlatency transport (QoS off)", config=LOW_LATENCY),
    Variant("direct callbacks both ends", ping="direct", echo="direct"),
    Variant("recv threads both ends", ping="recv", echo="recv"),
    Variant("direct, thread states kept", ping="kept", echo="kept"),
    Variant("direct, thread states kept, lowlatency", ping="kept", echo="kept", config=LOW_LATENCY),
    Variant("recv ping, direct echo", ping="recv", echo="direct"),
    Variant("recv ping, direct echo, lowlatency", ping="recv", echo="direct", config=LOW_LATENCY),
    Variant("direct both ends, lowlatency", ping="direct", echo="direct", config=LOW_LATENCY),
    Variant("one rx thread", env=ONE_RX),
    Variant(
        "direct both ends, lowlatency, one rx thread",
        ping="direct",
        echo="direct",
        config=LOW_LATENCY,
        env=ONE_RX,
    ),
    Variant(
        "recv ping, direct echo, lowlatency, one rx thread",
        ping="recv",
        echo="direct",
        config=LOW_LATENCY,
        env=ONE_RX,
    ),
    Variant("ours: Node defaults", layer="ours"),
    Variant("ours: ping only", layer="ours_ping"),
    Variant("ours: echo only", layer="ours_echo"),
    Variant("ours: direct callbacks both ends", ping="direct", echo="direct", layer="ours"),
    Variant("ours: low_latency, two rx threads", config=LOW_LATENCY, env=TWO_RX, layer="ours"),
    Variant("ours: low_latency (one rx thread)", config=LOW_LATENCY, layer="ours"),
    Variant(
        "ours: low_latency, direct callbacks",
        ping="direct",
        echo="direct",
        config=LOW_LATENCY,
        layer="ours",
    ),
    Variant("through a router", router=True),
    Variant("through a router, direct callbacks", ping="direct", echo="direct", router=True),
)
SOCKET = "socket (rospy's design, plain Python TCP)"


# ---- sessions ----


def session_config(variant: Variant, mode: str, connect: list[str], listen: list[str]):
    """The runtime's own session configuration plus the variant's knobs."""
    conf = zenoh_config(ZenohOptions(mode=mode, connect=connect, listen=listen))
    for key, value in variant.config.items():
        conf.insert_json5(key, value)
    return conf


def qos(variant: Variant) -> dict[str, object]:
    """The variant's publisher options."""
    return {
        "priority": getattr(zenoh.Priority, variant.priority),
        "congestion_control": getattr(zenoh.CongestionControl, variant.congestion),
        "express": variant.put == "express",
    }


def publisher(session: zenoh.Session, key: str, variant: Variant):
    """A ``put(bytes)`` for ``key`` in the variant's way."""
    options = qos(variant)
    if variant.encoding:
        options["encoding"] = encoding_for(CompressedImage)
    if variant.put == "session":
        return lambda payload: session.put(key, payload, **options)
    return session.declare_publisher(key, **options).put


def subscribe(session: zenoh.Session, key: str, how: str, on_payload):
    """Subscribe ``on_payload(bytes)`` to ``key``; for ``recv`` the subscriber is returned
    and the caller receives itself."""
    if how == "recv":
        return session.declare_subscriber(key, zenoh.handlers.FifoChannel(64))
    if how == "kept":  # direct, and Zenoh's thread keeps its Python thread state

        def on_sample(sample: zenoh.Sample) -> None:
            KEPT.keep()
            on_payload(sample.payload.to_bytes())

        return session.declare_subscriber(key, zenoh.handlers.Callback(on_sample, indirect=False))
    handler = zenoh.handlers.Callback(
        lambda sample: on_payload(sample.payload.to_bytes()), indirect=how == "indirect"
    )
    return session.declare_subscriber(key, handler)


# ---- the echo process ----


def node_for(variant: Variant, side: str, mode: str, connect: list[str], listen: list[str]):
    """Our runtime's Node for one end of an ``ours`` variant."""
    options = ZenohOptions(
        mode=mode,
        connect=connect,
        listen=listen,
        low_latency=variant.config.get("transport/unicast/lowlatency") == "true",
    )
    direct = getattr(variant, side) == "direct"
    return Node(f"breakdown_{side}", options, handle_signals=False, linger=0.0,
                direct_callbacks=direct)  # fmt: skip


def small_message() -> CompressedImage:
    """64 bytes of data in a typed message, stamped now."""
    return CompressedImage(header=Header.now("small"), format="raw", data=DATA)


PAYLOAD = codec.encode(small_message())
"""What plain Zenoh sends: the encoded typed message (so an ``ours`` end decodes it)."""


def serve_echo(variant: Variant, mode: str, connect: list[str], listen: list[str]) -> None:
    """In the child: put every ping back as a pong until stdin closes."""
    if variant.layer in ("ours", "ours_echo"):
        with node_for(variant, "echo", mode, connect, listen) as node:
            pub = node.publisher(registry.IMAGE_COMPRESSED, key=PONG_KEY, qos=qos(variant))
            node.subscribe(registry.IMAGE_COMPRESSED, pub.put, key=PING_KEY)
            print("ready", flush=True)
            sys.stdin.read()
        return
    session = zenoh.open(session_config(variant, mode, connect, listen))
    put = publisher(session, PONG_KEY, variant)
    sub = subscribe(session, PING_KEY, variant.echo, put)
    reader = None
    if variant.echo == "recv":

        def loop() -> None:
            try:
                while True:
                    put(sub.recv().payload.to_bytes())
            except zenoh.ZError:  # the session closed: the channel is empty and closed
                return

        reader = threading.Thread(target=loop, daemon=True)
        reader.start()
    print("ready", flush=True)
    sys.stdin.read()
    session.close()
    if reader is not None:
        reader.join(2.0)


def serve_socket() -> None:
    """In the child: a TCP echo with one reader thread, as a TCPROS connection has."""
    server = socket.create_server(("127.0.0.1", 0))
    print(server.getsockname()[1], flush=True)
    conn, _ = server.accept()
    conn.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)

    def loop() -> None:
        while True:
            head = conn.recv(4, socket.MSG_WAITALL)
            if len(head) < 4:
                return
            (size,) = struct.unpack("<I", head)
            data = conn.recv(size, socket.MSG_WAITALL)
            conn.sendall(struct.pack("<I", len(data)) + data)

    reader = threading.Thread(target=loop, daemon=True)
    reader.start()
    sys.stdin.read()
    conn.close()
    server.close()


# ---- the measuring process ----


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
