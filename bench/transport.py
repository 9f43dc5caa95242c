"""Transport benchmark: round-trip latency and throughput between two processes over Zenoh.

Measures the whole middleware path (typed publisher -> msgspec MessagePack -> Zenoh -> decode at
the boundary -> callback) for 64 bytes of data, a PoseStamped (~170 B) and a 640x480 bgr8 Image
(921,600 B of pixels), through the loopback router (client -> router -> client), peer to peer
(two peers, direct link), and peer to peer with ``ZenohOptions.low_latency`` on both ends, with
Zenoh shared memory on (the default for local processes).

With Debian's ROS 1 installed (``apt-get install python3-rospy python3-sensor-msgs
python3-rosmaster``; it runs under the system Python) it measures rospy in the same run
(``bench/rospy_transport.py``) and prints ours / rospy for the 64-byte and 640x480 messages,
round trips and messages per second, for both peer-to-peer paths. It ends with the 64-byte
round trip's breakdown (``bench.transport_breakdown``: plain zenoh-python variants, thread
hand-offs per round trip). Targets: images <= 0.65 ms and >= 3,700 images/s between local
processes; small messages <= 0.3 ms.

    python -m bench.transport [--samples-small 2000] [--samples-image 400] [--seconds 4]
                              [--breakdown-rounds 3]

Size: the measuring process and the peers it starts (serve, serve_raw) are one module, so that
every topology runs the same code on both ends.
"""

from __future__ import annotations

import argparse
import json
import math
import shutil
import subprocess
import sys
import threading
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import zenoh

from bench import transport_breakdown
from bench.breakdown_variants import SUMMARY
from bench.common import percentiles, print_table, write_results
from dronewrapper.msgs import CompressedImage, Header, Image, PoseStamped, codec, registry
from dronewrapper.router import router_options, run_router
from dronewrapper.runtime import Node, ZenohOptions
from dronewrapper.runtime.arguments import CommandParser, first_line

PING_NS, PONG_NS = "bench_ping", "bench_pong"
BLOCK = {"congestion_control": zenoh.CongestionControl.BLOCK}


def _free_endpoint() -> str:
    import socket

    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return f"tcp/127.0.0.1:{s.getsockname()[1]}"


_FRAME = np.random.default_rng(0).integers(0, 255, (480, 640, 3), dtype=np.uint8).tobytes()


KINDS = ("small", "pose", "image")
"""64 bytes of data (a CompressedImage too small for shared memory), a PoseStamped, a frame."""
SMALL = bytes(64)


def make_message(kind: str) -> Image | PoseStamped | CompressedImage:
    """A fresh message stamped now (the pixels are shared, not copied)."""
    if kind == "small":
        return CompressedImage(header=Header.now("small"), format="raw", data=SMALL)
    if kind == "pose":
        return PoseStamped(header=Header.now("map"))
    return Image(header=Header.now("cam_frontal"), height=480, width=640, encoding="bgr8",
                 step=640 * 3, data=_FRAME)  # fmt: skip


def _topic(kind: str):
    topics = {"small": registry.IMAGE_COMPRESSED, "pose": registry.LOCAL_POSE}
    return topics.get(kind, registry.IMAGE_RAW)


def _key(kind: str, ns: str) -> str:
    topic = _topic(kind)
    cameras = {"image": "cam_frontal", "small": "cam_small"}
    return topic.key(ns, camera=cameras[kind]) if kind in cameras else topic.key(ns)


# ---- the peer process (pong / sink) ----


def serve(role: str, options: ZenohOptions) -> None:
    """Run in the child: echo pings back (pong) or count messages (sink) until stdin closes."""
    if role == "rawpong":
        return serve_raw(options)
    with Node(f"bench_{role}", options, handle_signals=False, linger=0.0) as node:
        counts = dict.fromkeys(KINDS, 0)
        first_last = {kind: [0.0, 0.0] for kind in KINDS}
        one_way: dict[str, list[float]] = {kind: [] for kind in KINDS}
        for kind in KINDS:
            if role == "pong":
                pub = node.publisher(_topic(kind), key=_key(kind, PONG_NS), qos=BLOCK)

                def echo(msg, pub=pub, kind=kind):
                    one_way[kind].append(time.time() - msg.header.stamp)
                    pub.put(msg)

                node.subscribe(_topic(kind), echo, key=_key(kind, PING_NS))
            else:

                def count(_msg, kind=kind):
                    now = time.perf_counter()
                    if counts[kind] == 0:
                        first_last[kind][0] = now
                    first_last[kind][1] = now
                    counts[kind] += 1

                node.subscribe(_topic(kind), count, key=_key(kind, PING_NS))
        print("ready", flush=True)
        for line in sys.stdin:  # the parent asks for counts, then closes stdin
            kind, _, what = line.strip().partition(" ")
            if kind == "fallbacks":
                print(shm_fallbacks(node), flush=True)
                continue
            if what == "one_way":
                lat = np.asarray(one_way[kind][50:]) * 1e3
                print(f"{np.percentile(lat, 50):.6f} {np.percentile(lat, 99):.6f}", flush=True)
                continue
            n = counts[kind]
            span = first_last[kind][1] - first_last[kind][0]
            print(f"{n} {span:.6f}", flush=True)
            counts[kind] = 0


def shm_fallbacks(node: Node) -> int:
    """Images this node put the ordinary way because its shared-memory pool had no room."""
    return node.shm_writer.fallbacks if node.shm_writer is not None else 0


def serve_raw(options: ZenohOptions) -> None:
    """Baseline echo with plain Zenoh: copy the payload out and put it back, no decoding."""
    with Node("bench_rawpong", options, handle_signals=False, linger=0.0) as node:
        pubs = {
            kind: node.session.declare_publisher(_key(kind, PONG_NS), **BLOCK) for kind in KINDS
        }
        for kind in KINDS:
            node.session.declare_subscriber(
                _key(kind, PING_NS),
                lambda sample, pub=pubs[kind]: pub.put(sample.payload.to_bytes()),
            )
        print("ready", flush=True)
        for _ in sys.stdin:
            pass


def timed_pings(
    put: Callable[[Any], object],
    make: Callable[[], Any],
    got: threading.Event,
    samples: int,
    warmup: int,
    what: str,
    within_s: float = math.inf,
) -> list[float]:
    """Round trips (s) of ``put(make())`` until ``got`` is set (``make`` is not timed),
    ``warmup`` untimed ones first; fewer than ``samples`` once ``within_s`` real s went by."""
    rtts = []
    deadline = time.monotonic() + within_s
    for i in range(warmup + samples):
        got.clear()
        msg = make()
        t0 = time.perf_counter()
        put(msg)
        if not got.wait(2.0):
            raise RuntimeError(f"{what} ping {i} got no pong within 2 s")
        if i >= warmup:
            rtts.append(time.perf_counter() - t0)
        if time.monotonic() > deadline:
            break
    return rtts


def raw_round_trips(session: zenoh.Session, kind: str, samples: int, warmup: int = 50):
    """Round trips of plain bytes of the typed message's size (the Zenoh-only floor)."""
    got = threading.Event()

    def on_pong(sample: zenoh.Sample) -> None:
        sample.payload.to_bytes()
        got.set()

    sub = session.declare_subscriber(_key(kind, PONG_NS), on_pong)
    pub = session.declare_publisher(_key(kind, PING_NS), **BLOCK)
    payload = bytes(len(codec.encode(make_message(kind))))
    rtts = timed_pings(pub.put, lambda: payload, got, samples, warmup, f"raw {kind}")
    sub.undeclare()
    pub.undeclare()
    return rtts


# ---- the measuring process ----


class Peer:
    """The child process (pong or sink) over a pipe."""

    def __init__(
        self, role: str, mode: str, connect: list[str], listen: list[str], low_latency: bool
    ) -> None:
        args = [sys.executable, "-m", "bench.transport", "--serve", role, "--mode", mode]
        if low_latency:
            args.append("--low-latency")
        for ep in connect:
            args += ["--connect", ep]
        for ep in listen:
            args += ["--listen", ep]
        self.proc = subprocess.Popen(args, stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True)
        assert self.proc.stdout.readline().strip() == "ready"

    def ask(self, kind: str) -> tuple[int, float]:
        self.proc.stdin.write(kind + "\n")
        self.proc.stdin.flush()
        n, span = self.proc.stdout.readline().split()
        return int(n), float(span)

    def one_way(self, kind: str) -> dict[str, float]:
        self.proc.stdin.write(f"{kind} one_way\n")
        self.proc.stdin.flush()
        p50, p99 = self.proc.stdout.readline().split()
        return {"p50_ms": float(p50), "p99_ms": float(p99)}

    def fallbacks(self) -> int:
        self.proc.stdin.write("fallbacks\n")
        self.proc.stdin.flush()
        return int(self.proc.stdout.readline())

    def close(self) -> None:
        self.proc.stdin.close()
        self.proc.wait(20)


def round_trips(node: Node, kind: str, samples: int, warmup: int = 50) -> list[float]:
    got = threading.Event()
    node.subscribe(_topic(kind), lambda _m: got.set(), key=_key(kind, PONG_NS))
    pub = node.publisher(_topic(kind), key=_key(kind, PING_NS), qos=BLOCK)
    return timed_pings(pub.put, lambda: make_message(kind), got, samples, warmup, kind, 120.0)


def throughput(node: Node, sink: Peer, kind: str, seconds: float) -> dict[str, float]:
    pub = node.publisher(_topic(kind), key=_key(kind, PING_NS), qos=BLOCK)
    msg = make_message(kind)
    sent = 0
    end = time.monotonic() + seconds
    while time.monotonic() < end:
        pub.put(msg)
        sent += 1
    time.sleep(1.0)  # let the last messages arrive before counting
    received, span = sink.ask(kind)
    rate = (received - 1) / span if span > 0 else 0.0
    return {"sent": sent, "received": received, "msgs_per_s": rate}


def run_topology(name: str, args: argparse.Namespace) -> dict[str, object]:
    """Every figure of one path: ``router`` (both through a loopback router), ``p2p`` (peer to
    peer), ``p2p_low_latency`` (peer to peer with ``ZenohOptions.low_latency`` on both ends;
    measured from a fresh process, see :func:`low_latency_topology`; small messages only: the
    low-latency transport carries no message over 64 KB outside shared memory)."""
    low_latency = name == "p2p_low_latency"
    kinds = ("small", "pose") if low_latency else KINDS
    stop, ready = threading.Event(), threading.Event()
    router_thread = None
    if name == "router":
        endpoint = _free_endpoint()
        router_thread = threading.Thread(
            target=run_router, args=(router_options([endpoint]), stop, ready), daemon=True
        )
        router_thread.start()
        ready.wait(10)
        peer_mode, peer_connect, peer_listen = "client", [endpoint], []
        mine = ZenohOptions(mode="client", connect=[endpoint])
    else:  # peer to peer: the child listens, this process connects to it directly
        endpoint = _free_endpoint()
        peer_mode, peer_connect, peer_listen = "peer", [], [endpoint]
        mine = ZenohOptions(mode="peer", connect=[endpoint], low_latency=low_latency)
    result: dict[str, object] = {}
    raw = Peer("rawpong", peer_mode, peer_connect, peer_listen, low_latency)
    with Node("bench_rawping", mine, handle_signals=False, linger=0.0) as node:
        time.sleep(1.0)
        for kind in kinds:
            samples = args.samples_image if kind == "image" else args.samples_small
            result[f"raw_{kind}_rtt"] = percentiles(raw_round_trips(node.session, kind, samples))
    raw.close()
    pong = Peer("pong", peer_mode, peer_connect, peer_listen, low_latency)
    with Node("bench_ping", mine, handle_signals=False, linger=0.0) as node:
        time.sleep(1.0)
        for kind in kinds:
            samples = args.samples_image if kind == "image" else args.samples_small
            result[f"{kind}_rtt"] = percentiles(round_trips(node, kind, samples))
        fallbacks = {"ping": shm_fallbacks(node)}
    for kind in kinds:
        result[f"{kind}_one_way"] = pong.one_way(kind)
    fallbacks["pong"] = pong.fallbacks()
    pong.close()
    sink = Peer("sink", peer_mode, peer_connect, peer_listen, low_latency)
    with Node("bench_source", mine, handle_signals=False, linger=0.0) as node:
        time.sleep(1.0)
        for kind in ("image", "pose", "small"):
            if kind in kinds:
                result[f"{kind}_throughput"] = throughput(node, sink, kind, args.seconds)
        fallbacks["source"] = shm_fallbacks(node)
    sink.close()
    result["shm_fallbacks"] = fallbacks
    stop.set()
    if router_thread:
        router_thread.join(10)
    return result


def low_latency_topology(args: argparse.Namespace) -> dict[str, object]:
    """``run_topology("p2p_low_latency")`` in a fresh process: a low-latency session sets
    Zenoh's runtime up (one receive thread) only when it is its process's first session."""
    done = subprocess.run(
        [sys.executable, "-m", "bench.transport", "--topology", "p2p_low_latency",
         "--samples-small", str(args.samples_small), "--samples-image", str(args.samples_image),
         "--seconds", str(args.seconds)],
        capture_output=True, text=True, timeout=600, check=True,
    )  # fmt: skip
    return json.loads(done.stdout.strip().splitlines()[-1])


LABELS = {"small": "64 B", "pose": "PoseStamped", "image": "Image 640x480"}
SYSTEM_PYTHON = "/usr/bin/python3"


def rospy_available() -> bool:
    """Debian's ROS 1 (rospy, sensor_msgs, rosmaster) under the system Python."""
    try:
        probe = subprocess.run(
            [SYSTEM_PYTHON, "-c", "import rospy, sensor_msgs.msg, std_msgs.msg"],
            capture_output=True, timeout=60,
        )  # fmt: skip
    except (OSError, subprocess.TimeoutExpired):
        return False
    return probe.returncode == 0 and shutil.which("rosmaster") is not None


def rospy_side_by_side(results: dict, args: argparse.Namespace) -> dict | None:
    """rospy's figures in the same run (bench/rospy_transport.py) and ours / rospy, or None
    without ROS 1 (``apt-get install python3-rospy python3-sensor-msgs python3-rosmaster``)."""
    if not rospy_available():
        print("\nrospy: not installed (apt-get install python3-rospy python3-sensor-msgs "
              "python3-rosmaster), no side by side")  # fmt: skip
        return None
    done = subprocess.run(
        [SYSTEM_PYTHON, str(Path(__file__).with_name("rospy_transport.py")), "--small",
         str(args.samples_small), "--image", str(args.samples_image), "--seconds",
         str(args.seconds)], capture_output=True, text=True, timeout=600,
    )  # fmt: skip
    if done.returncode != 0:
        print(f"\nrospy: failed: {done.stderr[-500:]}")
        return None
    ros = json.loads(done.stdout.strip().splitlines()[-1])
    theirs = {
        "64 B RTT p50 (ms)": ros["small_rtt_ms"]["p50_ms"],
        "640x480 RTT p50 (ms)": ros["image_rtt_ms"]["p50_ms"],
        "64 B msgs/s": ros["small_per_s"],
        "640x480 images/s": ros["images_per_s"],
    }
    rows, ratios = [], {}
    for path in ("p2p", "p2p_low_latency"):
        res = results[path]
        ours = {
            "64 B RTT p50 (ms)": res["small_rtt"]["p50_ms"],
            "640x480 RTT p50 (ms)": res.get("image_rtt", {}).get("p50_ms"),
            "64 B msgs/s": res["small_throughput"]["msgs_per_s"],
            "640x480 images/s": res.get("image_throughput", {}).get("msgs_per_s"),
        }
        ours = {what: value for what, value in ours.items() if value is not None}
        ratios[path] = {what: ours[what] / theirs[what] for what in ours}
        rows += [[path, what, ours[what], theirs[what], ratios[path][what]] for what in ours]
    print_table(
        "ours (Zenoh peer to peer) side by side with rospy (TCPROS), same run, same machine",
        ["path", "figure", "ours", "rospy", "ours / rospy"],
        rows,
    )
    print(
        "  (round trips: lower is better; msgs/s: higher is better. rospy per 64 B round trip:\n"
        f"   {ros.get('small_switches_per_rtt') or 0:.1f} context switches, "
        f"{ros.get('small_migrations_per_rtt') or 0:.2f} moves between CPUs; ours: the "
        "breakdown below)"
    )
    return {"rospy": ros, "ratio": ratios}


def main(argv: list[str] | None = None) -> int:
    parser = CommandParser(description=first_line(__doc__))
    parser.add_argument("--samples-small", type=int, default=2000)
    parser.add_argument("--samples-image", type=int, default=400)
    parser.add_argument("--seconds", type=float, default=4.0)
    parser.add_argument(
        "--breakdown-rounds", type=int, default=3,
        help="rounds of the 64-byte breakdown (bench.transport_breakdown); 0: none",
    )  # fmt: skip
    parser.add_argument("--serve", choices=("pong", "sink", "rawpong"), help=argparse.SUPPRESS)
    parser.add_argument("--mode", default="client", help=argparse.SUPPRESS)
    parser.add_argument("--connect", action="append", default=[], help=argparse.SUPPRESS)
    parser.add_argument("--listen", action="append", default=[], help=argparse.SUPPRESS)
    parser.add_argument("--low-latency", action="store_true", help=argparse.SUPPRESS)
    parser.add_argument("--topology", help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.serve:
        options = ZenohOptions(
            mode=args.mode, connect=args.connect, listen=args.listen, low_latency=args.low_latency
        )
        serve(args.serve, options)
        return 0
    if args.topology:
        print(json.dumps(run_topology(args.topology, args)), flush=True)
        return 0

    results = {name: run_topology(name, args) for name in ("router", "p2p")}
    results["p2p_low_latency"] = low_latency_topology(args)
    rows = []
    for name, res in results.items():
        for kind, label in LABELS.items():
            if f"{kind}_rtt" not in res:
                continue
            rtt, one = res[f"{kind}_rtt"], res[f"{kind}_one_way"]
            raw = res[f"raw_{kind}_rtt"]
            rate = res[f"{kind}_throughput"]["msgs_per_s"]
            rows.append([name, label, raw["p50_ms"], rtt["p50_ms"], rtt["p99_ms"], one["p50_ms"],
                         one["p99_ms"], rate])  # fmt: skip
    print_table(
        "Zenoh through our runtime: typed publish -> MessagePack -> Zenoh -> decode (2 processes)",
        ["path", "message", "raw RTT p50", "RTT p50", "RTT p99", "1-way p50", "1-way p99",
         "msgs/s"],
        rows,
    )  # fmt: skip
    print(
        "  (ms; RTT = ping -> typed echo that decodes and re-publishes -> ping; raw = the same\n"
        "   sizes as plain bytes through plain Zenoh, measured in the same run: the floor;\n"
        "   SHM on; p2p_low_latency: ZenohOptions.low_latency on both ends, small messages only)"
    )
    for name, res in results.items():
        counts = ", ".join(f"{who} {n}" for who, n in res["shm_fallbacks"].items())
        print(f"  shared-memory puts that fell back to ordinary ones ({name}): {counts}")
    with_images = [r for r in results.values() if "image_rtt" in r]
    best_image_rtt = min(r["image_rtt"]["p50_ms"] for r in with_images)
    best_image_rate = max(r["image_throughput"]["msgs_per_s"] for r in with_images)
    best_pose_rtt = min(r["pose_rtt"]["p50_ms"] for r in results.values())
    targets = {
        "image_rtt_p50_ms<=0.65": best_image_rtt <= 0.65,
        "images_per_s>=3700": best_image_rate >= 3700,
        "pose_rtt_p50_ms<=0.3": best_pose_rtt <= 0.3,
    }
    print_table(
        "targets (best local path)", ["target", "met"], [[k, v] for k, v in targets.items()]
    )
    rospy_result = rospy_side_by_side(results, args)
    breakdown = None
    if args.breakdown_rounds > 0:
        breakdown = transport_breakdown.run(500, args.breakdown_rounds, list(SUMMARY))
        transport_breakdown.report(breakdown)
    write_results(
        "transport",
        {"results": results, "targets": targets, "rospy": rospy_result, "breakdown": breakdown},
    )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
