"""ROS 2 gateway: the latency it adds per message and its CPU with one drone's telemetry.

Runs the real gateway (``python -m dronewrapper_ros2_gateway``) as a peer on a router in this
process. A publisher session here sends our messages; a second session here (the receiver)
takes each twice: on our key (direct: one hop) and on the gateway's ROS 2 key (CDR, rmw_zenoh's
attachment: the hop to the gateway, its work, the hop back). For each message, added latency
= ROS 2 arrival - direct arrival (both on this process's CLOCK_MONOTONIC), so it is what a
ROS 2 subscriber waits beyond one of ours: the gateway's work and its extra hop.

* a PoseStamped at 50 Hz (target p50 <= 0.3 ms added), beside the same figure for a bare
  Python Zenoh relay (another process that puts each sample's bytes again on another key:
  the floor of any relay process, the hop without any work);
* a 640x480 bgr8 Image at 15 Hz (shared memory to the gateway, as on the drone);
* the gateway's own work per message, without the hops (decode, convert, CDR, attachment),
  timed here on the same code;
* the gateway's CPU share of one core (utime + stime from /proc) while a bridge's full
  telemetry flows at the registry's rates (state, extended state, pose, two velocities,
  global position, battery) and a ROS 2 subscriber takes every topic (target <= 5 %).

Run: ``.venv/bin/python -m bench.ros2_gateway [--seconds S]``; writes
bench/results/ros2_gateway.json.
"""

from __future__ import annotations

import argparse
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import numpy as np

from bench.common import (
    LoopbackRouter,
    cpu_seconds,
    percentiles,
    print_table,
    stop_process,
    write_results,
)
from dronewrapper.msgs import codec, registry
from dronewrapper.msgs.geometry import Point, Pose, PoseStamped, TwistStamped
from dronewrapper.msgs.mavros import ExtendedState, State
from dronewrapper.msgs.sensor import BatteryState, Image, NavSatFix
from dronewrapper.msgs.std import Header
from dronewrapper.ros2 import cdr
from dronewrapper.ros2.convert import ROS_TYPES
from dronewrapper.ros2.names import topic_key
from dronewrapper.ros2.typehash import type_hash
from dronewrapper.runtime import Node, ZenohOptions

REPO = Path(__file__).resolve().parents[1]
NS = "drone"
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


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=10.0, help="length of each phase")
    parser.add_argument(
        "--gateway-arg", action="append", default=[], help="an extra flag for the gateway"
    )
    args = parser.parse_args(argv)

    router = LoopbackRouter()
    if not router.start():
        print("router did not start", file=sys.stderr)
        return 1
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
    node = Node("bench", ZenohOptions(connect=[endpoint], namespace=NS), handle_signals=False)
    receiver = Node(
        "bench_rx", ZenohOptions(connect=[endpoint], namespace=NS), handle_signals=False
    )
    results: dict[str, object] = {}
    try:
        deadline = time.monotonic() + 30
        while not node.alive_services(NS, timeout=0.5) >= {f"{NS}/alive/ros2_gateway"}:
            if time.monotonic() > deadline or gateway.poll() is not None:
                print("the gateway did not start", file=sys.stderr)
                return 1
        time.sleep(1.0)

        # pose: 50 Hz, marker in position.x
        pose_pub = node.publisher(registry.LOCAL_POSE)
        pose = Arrivals(
            receiver, registry.LOCAL_POSE.key(NS), PoseStamped,
            lambda m: int(m.pose.position.x), lambda v: int(v["pose"]["position"]["x"]),
        )  # fmt: skip
        relayed: dict[int, float] = {}

        def on_relayed(sample) -> None:
            now = time.monotonic()
            msg = codec.decode(PoseStamped, sample.payload.to_bytes())
            relayed.setdefault(int(msg.pose.position.x), now)

        relay_sub = receiver.session.declare_subscriber(relay_key, on_relayed)
        time.sleep(0.5)
        stream(
            lambda i: pose_pub.put(
                PoseStamped(header=Header.now("map"), pose=Pose(position=Point(x=float(i))))
            ),
            50.0,
            args.seconds,
        )
        time.sleep(0.3)
        pose.close()
        relay_sub.undeclare()
        relay_added = percentiles([relayed[m] - t for m, t in pose.direct.items() if m in relayed])

        # image: 640x480 bgr8 at 15 Hz, marker in header.stamp (whole seconds)
        image_pub = node.publisher(registry.IMAGE_RAW, camera="cam_frontal")
        frame = np.random.default_rng(1).integers(0, 255, (480, 640, 3), dtype=np.uint8)
        image = Arrivals(
            receiver, registry.IMAGE_RAW.key(NS, camera="cam_frontal"), Image,
            lambda m: int(m.header.stamp), lambda v: int(v["header"]["stamp"]["sec"]),
        )  # fmt: skip
        time.sleep(1.5)  # the gateway sees the ROS 2 subscriber and subscribes to the camera
        stream(
            lambda i: image_pub.put(
                Image(header=Header(stamp=float(i)), height=480, width=640, step=1920,
                      data=frame.tobytes())
            ),
            15.0,
            args.seconds,
        )  # fmt: skip
        time.sleep(0.3)
        image.close()
        time.sleep(1.5)  # the gateway drops the camera again

        # CPU: one drone's full telemetry at the registry's rates, every ROS 2 topic subscribed
        pubs = [(node.publisher(topic), msg_type, topic.rate_hz) for topic, msg_type in TELEMETRY]
        received = [0]

        def on_any(_sample) -> None:
            received[0] += 1

        subs = [
            receiver.session.declare_subscriber(ros_key_of(topic.key(NS), t), on_any)
            for topic, t in TELEMETRY
        ]
        idle0, w0 = cpu_seconds(gateway.pid), time.monotonic()
        time.sleep(min(args.seconds, 5.0))
        idle_cpu = (cpu_seconds(gateway.pid) - idle0) / (time.monotonic() - w0)
        stop = threading.Event()
        sent = [0]

        def telemetry() -> None:
            start, due = time.monotonic(), [0.0] * len(pubs)
            while not stop.is_set():
                now = time.monotonic() - start
                for i, (pub, msg_type, rate) in enumerate(pubs):
                    if now >= due[i]:
                        pub.put(msg_type(header=Header.now("map")))
                        sent[0] += 1
                        due[i] += 1.0 / rate
                stop.wait(0.002)

        thread = threading.Thread(target=telemetry, daemon=True)
        thread.start()
        time.sleep(1.0)
        c0, w0, s0, r0 = cpu_seconds(gateway.pid), time.monotonic(), sent[0], received[0]
        time.sleep(args.seconds)
        elapsed = time.monotonic() - w0
        busy_cpu = (cpu_seconds(gateway.pid) - c0) / elapsed
        rate_in, rate_out = (sent[0] - s0) / elapsed, (received[0] - r0) / elapsed
        stop.set()
        thread.join()
        for sub in subs:
            sub.undeclare()

        pose_added, image_added = percentiles(pose.added()), percentiles(image.added())
        pose_work = work_per_message(PoseStamped(header=Header.now("map")))
        image_work = work_per_message(
            Image(header=Header.now("cam"), height=480, width=640, step=1920,
                  data=frame.tobytes()), repeat=200,
        )  # fmt: skip
        results = {
            "pose_added_latency": {**pose_added, "sent": len(pose.direct), "target_p50_ms": 0.3},
            "bare_relay_pose_added_latency": relay_added,
            "image_640x480_added_latency": {**image_added, "sent": len(image.direct)},
            "gateway_work_pose": pose_work,
            "gateway_work_image_640x480": image_work,
            "cpu_one_core": {
                "idle": round(idle_cpu, 4),
                "full_telemetry": round(busy_cpu, 4),
                "messages_in_per_s": round(rate_in, 1),
                "ros2_messages_out_per_s": round(rate_out, 1),
                "target": 0.05,
            },
        }
        print_table(
            "ROS 2 gateway: added latency (ROS 2 arrival - direct arrival)",
            ["message", "n", "p50 ms", "p90 ms", "p99 ms", "max ms"],
            [
                ["PoseStamped", pose_added["n"], pose_added["p50_ms"], pose_added["p90_ms"],
                 pose_added["p99_ms"], pose_added["max_ms"]],
                ["PoseStamped, bare relay", relay_added["n"], relay_added["p50_ms"],
                 relay_added["p90_ms"], relay_added["p99_ms"], relay_added["max_ms"]],
                ["Image 640x480", image_added["n"], image_added["p50_ms"],
                 image_added["p90_ms"], image_added["p99_ms"], image_added["max_ms"]],
            ],
        )  # fmt: skip
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
                ["idle", idle_cpu, 0, 0],
                ["full telemetry", busy_cpu, round(rate_in, 1), round(rate_out, 1)],
            ],
        )
        write_results("ros2_gateway", results)
    finally:
        receiver.close()
        node.close()
        stop_process(gateway, signal.SIGTERM)
        relay.stdin.close()
        relay.wait(10)
        router.stop(10)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
