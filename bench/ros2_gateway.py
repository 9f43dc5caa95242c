"""ROS 2 gateway: the latency it adds per message and its CPU, standalone and hosted.

Two ways to present a drone to ROS 2 (docs/ros2.md), measured side by side on one router:

* **standalone**: the real gateway process (``python -m dronewrapper_ros2_gateway``) relays a
  publisher process's samples (drone ``drone``);
* **hosted**: the publisher process runs the gateway on its own session, as a bridge's process
  does with the gateway beside it (:func:`dronewrapper_ros2_gateway.hosted.hosted_gateway`;
  drone ``drone_h``).

Each publisher is a child process of this script (``--publisher``), the same code for both
modes, standing in for a bridge: it puts our messages from its main thread. A receiver session
in this process takes each message twice: on our key (direct, one hop) and on its ROS 2 key
(CDR, rmw_zenoh's attachment). Added latency = ROS 2 arrival - direct arrival (both on this
process's CLOCK_MONOTONIC): what a ROS 2 subscriber waits beyond one of ours.

* a PoseStamped at 50 Hz (target p50 <= 0.3 ms added), beside the same figure for a bare
  Python Zenoh relay (another process that puts each sample's bytes again on another key:
  the floor of any relay process, the hop without any work);
* a 640x480 bgr8 Image at 15 Hz (shared memory to the standalone gateway, as on the drone);
* the gateway's own work per message, without the hops (decode, convert, CDR, attachment),
  timed here on the same code;
* CPU, share of one core (utime + stime from /proc), while a bridge's full telemetry flows at
  the registry's rates (state, extended state, pose, two velocities, global position, battery)
  and a ROS 2 subscriber takes every topic (target <= 5 %): standalone, the gateway process's;
  hosted, the hosting publisher's minus the plain publisher's in the same phase.

Run: ``.venv/bin/python -m bench.ros2_gateway [--seconds S]``; writes
bench/results/ros2_gateway.json.

Size: the parent and the publisher child it starts (--publisher) are one script, so that both
modes run the same publisher code and both phases read the same arrivals.
"""

from __future__ import annotations

import argparse
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

from bench.common import (
    cpu_seconds,
    percentiles,
    print_table,
    started_router,
    stop_process,
    write_results,
)
from dronewrapper.msgs import codec, registry
from dronewrapper.msgs.geometry import Point, Pose, PoseStamped, TwistStamped
from dronewrapper.msgs.mavros import ExtendedState, State
from dronewrapper.msgs.sensor import BatteryState, Image, NavSatFix
from dronewrapper.msgs.std import Header
from dronewrapper.runtime import Node, ZenohOptions
from dronewrapper.runtime.arguments import CommandParser, first_line
from dronewrapper_ros2_codec import cdr
from dronewrapper_ros2_codec.convert import ROS_TYPES
from dronewrapper_ros2_codec.names import topic_key
from dronewrapper_ros2_codec.typehash import type_hash

REPO = Path(__file__).resolve().parents[1]
NS = "drone"  # the standalone gateway's drone
NS_HOSTED = "drone_h"  # the hosting publisher's drone
POSE_HZ, IMAGE_HZ = 50.0, 15.0
CAMERA = "cam_frontal"
TELEMETRY = [
    (registry.STATE, State),
    (registry.EXTENDED_STATE, ExtendedState),
    (registry.LOCAL_POSE, PoseStamped),
    (registry.VELOCITY_BODY, TwistStamped),
    (registry.VELOCITY_LOCAL, TwistStamped),
    (registry.GLOBAL_POSITION, NavSatFix),
    (registry.BATTERY, BatteryState),
]


RELAY = """
import sys, threading, zenoh
conf = zenoh.Config()
conf.insert_json5("mode", '"peer"')
conf.insert_json5("connect/endpoints", '["%s"]' % sys.argv[1])
conf.insert_json5("listen/endpoints", '["tcp/127.0.0.1:0"]')
conf.insert_json5("scouting/multicast/enabled", "false")
with zenoh.open(conf) as session:
    pub = session.declare_publisher(sys.argv[3], express=True)
    sub = session.declare_subscriber(sys.argv[2], lambda s: pub.put(s.payload))
    sys.stdin.read()
"""
"""A bare relay: every sample on argv[2] put again on argv[3] (until stdin closes)."""


def frame() -> np.ndarray:
    return np.random.default_rng(1).integers(0, 255, (480, 640, 3), dtype=np.uint8)


def stream(publish, rate_hz: float, seconds: float) -> int:
    """Call ``publish(marker)`` at ``rate_hz`` for ``seconds``; the number published."""
    start = time.monotonic()
    marker = 0
    while time.monotonic() - start < seconds:
        marker += 1
        publish(marker)
        next_at = start + marker / rate_hz
        time.sleep(max(0.0, next_at - time.monotonic()))
    return marker


def telemetry(pubs, seconds: float) -> int:
    """Put each (publisher, type, rate) at its rate for ``seconds``; the number put."""
    start, due, sent = time.monotonic(), [0.0] * len(pubs), 0
    while (now := time.monotonic() - start) < seconds:
        for i, (pub, msg_type, rate) in enumerate(pubs):
            if now >= due[i]:
                pub.put(msg_type(header=Header.now("map")))
                sent += 1
                due[i] += 1.0 / rate
        time.sleep(0.002)
    return sent


def timed_poses(publisher, seconds: float) -> tuple[int, float, float]:
    """Put a marked pose at ``POSE_HZ`` for ``seconds``; the number put and the p50 and p90 of
    each ``put`` call's time (µs)."""
    puts: list[float] = []

    def put(i: int) -> None:
        msg = PoseStamped(header=Header.now("map"), pose=Pose(position=Point(x=float(i))))
        t0 = time.perf_counter()
        publisher.put(msg)
        puts.append((time.perf_counter() - t0) * 1e6)

    n = stream(put, POSE_HZ, seconds)
    p50, p90 = np.percentile(puts, [50, 90])
    return n, float(p50), float(p90)


def publisher_main(endpoint: str, ns: str, hosted: bool) -> int:
    """The child: a stand-in for a bridge on ``endpoint`` (drone ``ns``; hosting the gateway
    when ``hosted``). Reads ``pose|image|telemetry SECONDS`` lines on stdin, answers each with
    ``done N`` once published (a pose phase adds the p50 and p90 of its ``put`` calls' time,
    µs: what a bridge's thread spends in them); ``ready`` once declared."""
    from dronewrapper_ros2_gateway.config import Config
    from dronewrapper_ros2_gateway.hosted import hosted_gateway

    options = ZenohOptions(connect=[endpoint], namespace=ns)
    with (
        Node("bench_publisher", options, handle_signals=False) as node,
        hosted_gateway(node, Config() if hosted else None),
    ):
        pose = node.publisher(registry.LOCAL_POSE)
        image = node.publisher(registry.IMAGE_RAW, camera=CAMERA)
        pubs = [(node.publisher(topic), msg_type, topic.rate_hz) for topic, msg_type in TELEMETRY]
        data = frame().tobytes()
        print("ready", flush=True)
        for line in sys.stdin:
            what, seconds = line.split()
            if what == "pose":
                n, p50, p90 = timed_poses(pose, float(seconds))
                print(f"done {n} {p50:.2f} {p90:.2f}", flush=True)
                continue
            elif what == "image":
                n = stream(
                    lambda i: image.put(
                        Image(header=Header(stamp=float(i)), height=480, width=640,
                              step=1920, data=data)
                    ),
                    IMAGE_HZ,
                    float(seconds),
                )  # fmt: skip
            else:
                n = telemetry(pubs, float(seconds))
            print(f"done {n}", flush=True)
    return 0


class Publisher:
    """A publisher child process and its stdin/stdout protocol."""

    def __init__(self, endpoint: str, ns: str, hosted: bool) -> None:
        argv = [sys.executable, "-m", "bench.ros2_gateway", "--publisher", endpoint, ns]
        self.proc = subprocess.Popen(
            [*argv, *(["--hosted"] if hosted else [])],
            cwd=REPO,
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            text=True,
        )
        self.ready = self.proc.stdout.readline().strip() == "ready"

    def run(self, what: str, seconds: float) -> tuple[int, list[float]]:
        """Ask for ``what`` for ``seconds``; the number of messages put, and the phase's
        figures (pose: the put time's p50 and p90, µs)."""
        self.proc.stdin.write(f"{what} {seconds}\n")
        self.proc.stdin.flush()
        _, n, *figures = self.proc.stdout.readline().split()
        return int(n), [float(f) for f in figures]

    def cpu(self) -> float:
        return cpu_seconds(self.proc.pid)

    def close(self) -> None:
        self.proc.stdin.close()
        self.proc.wait(15)


def ros_key_of(key: str, msg_type: type) -> str:
    ros_type = ROS_TYPES[msg_type]
    return topic_key(0, "/" + key, ros_type, type_hash(ros_type))


class Arrivals:
    """Arrival times by marker, on our key and on the ROS 2 key."""

    def __init__(self, node: Node, key: str, msg_type: type, marker_of_ours, marker_of_ros):
        self.direct: dict[int, float] = {}
        self.ros: dict[int, float] = {}
        ros_type = ROS_TYPES[msg_type]

        def on_direct(sample) -> None:
            now = time.monotonic()
            self.direct.setdefault(
                marker_of_ours(codec.decode(msg_type, sample.payload.to_bytes())), now
            )

        def on_ros(sample) -> None:
            now = time.monotonic()
            value = cdr.decode(ros_type, sample.payload.to_bytes())
            self.ros.setdefault(marker_of_ros(value), now)

        self._subs = [
            node.session.declare_subscriber(key, on_direct),
            node.session.declare_subscriber(ros_key_of(key, msg_type), on_ros),
        ]

    def added(self) -> list[float]:
        return [self.ros[m] - t for m, t in self.direct.items() if m in self.ros]

    def close(self) -> None:
        for sub in self._subs:
            sub.undeclare()


def pose_arrivals(receiver: Node, ns: str) -> Arrivals:
    return Arrivals(
        receiver, registry.LOCAL_POSE.key(ns), PoseStamped,
        lambda m: int(m.pose.position.x), lambda v: int(v["pose"]["position"]["x"]),
    )  # fmt: skip


def image_arrivals(receiver: Node, ns: str) -> Arrivals:
    return Arrivals(
        receiver, registry.IMAGE_RAW.key(ns, camera=CAMERA), Image,
        lambda m: int(m.header.stamp), lambda v: int(v["header"]["stamp"]["sec"]),
    )  # fmt: skip


def work_per_message(msg: object, repeat: int = 2000) -> dict[str, float]:
    """The gateway's own work on one sample (decode ours, convert, CDR, attachment), without
    any I/O: p50/p90 in microseconds, timed on the gateway's code with a publisher that only
    keeps the bytes."""
    from dronewrapper_ros2_gateway.node import Outgoing

    class Keep:
        def put(self, payload: bytes, *, attachment: bytes) -> None:
            self.last = payload

    out = Outgoing(Keep(), ROS_TYPES[type(msg)], bytes(16))
    raw, decoder = codec.encode(msg), codec.decoder(type(msg))
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        out(decoder.decode(raw))
        times.append(time.perf_counter() - t0)
    arr = np.asarray(times) * 1e6
    return {"p50_us": float(np.percentile(arr, 50)), "p90_us": float(np.percentile(arr, 90))}


def latency_phase(receiver: Node, publisher: Publisher, ns: str, seconds: float) -> dict:
    """Pose and image added latency of one drone's publisher (its mode: who relays ``ns``)."""
    pose = pose_arrivals(receiver, ns)
    time.sleep(0.5)
    _, (put_p50, put_p90) = publisher.run("pose", seconds)
    time.sleep(0.3)
    pose.close()
    image = image_arrivals(receiver, ns)
    time.sleep(1.5)  # the gateway sees the ROS 2 subscriber and subscribes to the camera
    publisher.run("image", seconds)
    time.sleep(0.3)
    image.close()
    time.sleep(1.5)  # the gateway drops the camera again
    return {
        "pose": {**percentiles(pose.added()), "sent": len(pose.direct)},
        "image": {**percentiles(image.added()), "sent": len(image.direct)},
        "pose_put_us": {"p50": put_p50, "p90": put_p90},
    }


def cpu_phase(receiver: Node, publisher: Publisher, ns: str, seconds: float, *pids: int):
    """CPU seconds per second of each of ``pids`` while ``publisher`` puts the full telemetry
    and a ROS 2 subscriber takes every topic; and the ROS 2 messages received per second."""
    received = [0]

    def on_any(_sample) -> None:
        received[0] += 1

    subs = [
        receiver.session.declare_subscriber(ros_key_of(topic.key(ns), t), on_any)
        for topic, t in TELEMETRY
    ]
    time.sleep(1.0)
    c0, w0 = [cpu_seconds(pid) for pid in pids], time.monotonic()
    sent, _ = publisher.run("telemetry", seconds)
    elapsed = time.monotonic() - w0
    shares = [(cpu_seconds(pid) - c) / elapsed for pid, c in zip(pids, c0, strict=True)]
    time.sleep(0.2)
    for sub in subs:
        sub.undeclare()
    return shares, sent / elapsed, received[0] / elapsed


def main(argv: list[str] | None = None) -> int:
    parser = CommandParser(description=first_line(__doc__))
    parser.add_argument("--seconds", type=float, default=10.0, help="length of each phase")
    parser.add_argument(
        "--gateway-arg", action="append", default=[], help="an extra flag for the gateway"
    )
    parser.add_argument("--publisher", nargs=2, metavar=("ENDPOINT", "NS"), help=argparse.SUPPRESS)
    parser.add_argument("--hosted", action="store_true", help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.publisher:
        return publisher_main(*args.publisher, hosted=args.hosted)

    router = started_router()
    endpoint = router.endpoint
    gateway = subprocess.Popen(
        [sys.executable, "-m", "dronewrapper_ros2_gateway", "--connect", endpoint,
         "--ns", NS, "--log-level", "WARNING", *args.gateway_arg],
        cwd=REPO,
    )  # fmt: skip
    relay_key = "bench/relay/pose"
    relay = subprocess.Popen(
        [sys.executable, "-c", RELAY, endpoint, registry.LOCAL_POSE.key(NS), relay_key],
        stdin=subprocess.PIPE,
    )
    plain = Publisher(endpoint, NS, hosted=False)
    hosted = Publisher(endpoint, NS_HOSTED, hosted=True)
    options = ZenohOptions(connect=[endpoint], namespace=NS)
    receiver = Node("bench_rx", options, handle_signals=False)
    try:
        if not (plain.ready and hosted.ready):
            print("a publisher did not start", file=sys.stderr)
            return 1
        deadline = time.monotonic() + 30
        while not receiver.alive_services(NS, timeout=0.5) >= {f"{NS}/alive/ros2_gateway"}:
            if time.monotonic() > deadline or gateway.poll() is not None:
                print("the gateway did not start", file=sys.stderr)
                return 1
        time.sleep(1.0)

        relayed: dict[int, float] = {}

        def on_relayed(sample) -> None:
            now = time.monotonic()
            msg = codec.decode(PoseStamped, sample.payload.to_bytes())
            relayed.setdefault(int(msg.pose.position.x), now)

        relay_sub = receiver.session.declare_subscriber(relay_key, on_relayed)
        direct = pose_arrivals(receiver, NS)  # the relay's reference (the gateway's phase)
        standalone = latency_phase(receiver, plain, NS, args.seconds)
        direct.close()
        relay_sub.undeclare()
        relay_added = percentiles(
            [relayed[m] - t for m, t in direct.direct.items() if m in relayed]
        )
        in_bridge = latency_phase(receiver, hosted, NS_HOSTED, args.seconds)

        idle0, w0 = cpu_seconds(gateway.pid), time.monotonic()
        time.sleep(min(args.seconds, 5.0))
        idle_cpu = (cpu_seconds(gateway.pid) - idle0) / (time.monotonic() - w0)
        (gateway_cpu, plain_cpu), rate_in, rate_out = cpu_phase(
            receiver, plain, NS, args.seconds, gateway.pid, plain.proc.pid
        )
        (hosted_cpu,), hosted_in, hosted_out = cpu_phase(
            receiver, hosted, NS_HOSTED, args.seconds, hosted.proc.pid
        )
        hosted_added_cpu = hosted_cpu - plain_cpu

        pose_work = work_per_message(PoseStamped(header=Header.now("map")))
        image_work = work_per_message(
            Image(header=Header.now("cam"), height=480, width=640, step=1920,
                  data=frame().tobytes()), repeat=200,
        )  # fmt: skip
        load = os.getloadavg()
        results = {
            "pose_added_latency": {**standalone["pose"], "target_p50_ms": 0.3},
            "hosted_pose_added_latency": {**in_bridge["pose"], "target_p50_ms": 0.3},
            "bare_relay_pose_added_latency": relay_added,
            "image_640x480_added_latency": standalone["image"],
            "hosted_image_640x480_added_latency": in_bridge["image"],
            "publisher_pose_put_us": standalone["pose_put_us"],
            "hosted_publisher_pose_put_us": in_bridge["pose_put_us"],
            "gateway_work_pose": pose_work,
            "gateway_work_image_640x480": image_work,
            "cpu_one_core": {
                "idle": round(idle_cpu, 4),
                "full_telemetry": round(gateway_cpu, 4),
                "messages_in_per_s": round(rate_in, 1),
                "ros2_messages_out_per_s": round(rate_out, 1),
                "target": 0.05,
            },
            "hosted_cpu_one_core": {
                "added_to_the_publisher": round(hosted_added_cpu, 4),
                "publisher_hosting": round(hosted_cpu, 4),
                "publisher_alone": round(plain_cpu, 4),
                "messages_in_per_s": round(hosted_in, 1),
                "ros2_messages_out_per_s": round(hosted_out, 1),
                "target": 0.05,
            },
            "loadavg_during": [round(x, 2) for x in load],
        }
        rows = []
        for name, figures in (
            ("PoseStamped, standalone", standalone["pose"]),
            ("PoseStamped, hosted", in_bridge["pose"]),
            ("PoseStamped, bare relay", relay_added),
            ("Image 640x480, standalone", standalone["image"]),
            ("Image 640x480, hosted", in_bridge["image"]),
        ):
            rows.append([name, figures["n"], figures["p50_ms"], figures["p90_ms"],
                         figures["p99_ms"], figures["max_ms"]])  # fmt: skip
        print_table(
            "ROS 2 gateway: added latency (ROS 2 arrival - direct arrival)",
            ["message", "n", "p50 ms", "p90 ms", "p99 ms", "max ms"],
            rows,
        )
        print_table(
            "The publisher's put of a pose (its thread's time in put)",
            ["publisher", "p50 us", "p90 us"],
            [
                ["plain (the standalone gateway relays it)", *standalone["pose_put_us"].values()],
                ["hosting the gateway", *in_bridge["pose_put_us"].values()],
            ],
        )
        print_table(
            "ROS 2 gateway: its own work per message (no I/O)",
            ["message", "p50 us", "p90 us"],
            [
                ["PoseStamped", pose_work["p50_us"], pose_work["p90_us"]],
                ["Image 640x480", image_work["p50_us"], image_work["p90_us"]],
            ],
        )
        print_table(
            "ROS 2 gateway: CPU (share of one core)",
            ["phase", "cpu", "in msg/s", "out msg/s"],
            [
                ["standalone, idle", idle_cpu, 0, 0],
                ["standalone, full telemetry", gateway_cpu, round(rate_in, 1), round(rate_out, 1)],
                ["hosted, added to the publisher", hosted_added_cpu, round(hosted_in, 1),
                 round(hosted_out, 1)],
            ],
        )  # fmt: skip
        print(f"\nload average (1, 5, 15 min): {load[0]:.2f} {load[1]:.2f} {load[2]:.2f}")
        write_results("ros2_gateway", results)
    finally:
        receiver.close()
        for child in (plain, hosted):
            child.close()
        stop_process(gateway, signal.SIGTERM)
        relay.stdin.close()
        relay.wait(10)
        router.stop(10)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
