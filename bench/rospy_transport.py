"""ROS 1 (rospy) side by side with ours: the same round trips and throughput over TCPROS.

Runs under the system Python where Debian's ROS 1 is installed (``apt-get install python3-rospy
python3-sensor-msgs python3-rosmaster``; rospy is not on PyPI), started by ``bench.transport``
when it finds it: ``/usr/bin/python3 bench/rospy_transport.py [--small N] [--image N]
[--seconds S]``. It starts a ROS master on a free port, a pong node in a child process (echoes
``/ping_*`` to ``/pong_*``, TCP_NODELAY on both sides), and measures from this node:

* the round trip of a 64-byte ``std_msgs/UInt8MultiArray`` payload (64 bytes of data) and of a
  640x480 ``bgr8`` ``sensor_msgs/Image``;
* images and 64-byte messages per second from this node to a counting subscriber in the
  child.

Prints one JSON object: ``{"small_rtt_ms": {...}, "image_rtt_ms": {...}, "images_per_s": x,
"small_per_s": x, "small_switches_per_rtt": n, "small_migrations_per_rtt": n}`` (the last
two: both nodes' threads' context switches and moves between CPUs per 64-byte round trip,
from ``/proc``, as ``bench.transport_breakdown`` counts them).
It does not import the project (the system Python has none of its dependencies).
"""

from __future__ import annotations

import argparse
import json
import os
import socket
import subprocess
import sys
import threading
import time

from dronewrapper.runtime.arguments import CommandParser, first_line


def percentiles_ms(values: list[float]) -> dict[str, float]:
    ordered = sorted(v * 1e3 for v in values)
    if not ordered:
        return {"n": 0}

    def at(q: float) -> float:
        return ordered[min(len(ordered) - 1, int(q * (len(ordered) - 1)))]

    return {"n": len(ordered), "p50_ms": at(0.5), "p90_ms": at(0.9), "p99_ms": at(0.99)}


def free_port() -> int:
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        return sock.getsockname()[1]


def pong() -> None:
    """The child: echo pings back, count flooded messages by kind, until stdin closes."""
    import rospy
    from sensor_msgs.msg import Image
    from std_msgs.msg import UInt8MultiArray

    rospy.init_node("bench_pong", anonymous=True, disable_signals=True)
    counts = {kind: {"n": 0, "first": 0.0, "last": 0.0} for kind in ("small", "image")}
    pubs = {
        "small": rospy.Publisher("/pong_small", UInt8MultiArray, queue_size=10, tcp_nodelay=True),
        "image": rospy.Publisher("/pong_image", Image, queue_size=10, tcp_nodelay=True),
    }
    rospy.Subscriber("/ping_small", UInt8MultiArray, pubs["small"].publish, tcp_nodelay=True)
    rospy.Subscriber("/ping_image", Image, pubs["image"].publish, tcp_nodelay=True)

    def counter(kind: str):
        def count(_msg) -> None:
            now = time.perf_counter()
            if counts[kind]["n"] == 0:
                counts[kind]["first"] = now
            counts[kind]["last"] = now
            counts[kind]["n"] += 1

        return count

    rospy.Subscriber("/flood_image", Image, counter("image"), queue_size=1000, tcp_nodelay=True)
    rospy.Subscriber(
        "/flood_small", UInt8MultiArray, counter("small"), queue_size=1000, tcp_nodelay=True
    )
    print("ready", flush=True)
    for line in sys.stdin:
        kind = line.strip()
        if kind in counts:
            print(json.dumps(counts[kind]), flush=True)
    rospy.signal_shutdown("done")


def _summed(pid: int, name: str, marker: str) -> int:
    """The sum of the last field of the lines holding ``marker`` in ``/proc/PID/task/*/name``
    (every thread of ``pid``; one that ended meanwhile is passed over)."""
    total = 0
    for task in os.listdir(f"/proc/{pid}/task"):
        try:
            with open(f"/proc/{pid}/task/{task}/{name}") as lines:
                total += sum(int(line.split()[-1]) for line in lines if marker in line)
        except (FileNotFoundError, ProcessLookupError):
            continue
    return total


def context_switches(pid: int) -> int:
    """Voluntary + involuntary context switches of every thread of ``pid`` so far."""
    return _summed(pid, "status", "ctxt_switches:")


def migrations(pid: int) -> int:
    """Moves of ``pid``'s threads from one CPU to another so far (``se.nr_migrations``)."""
    return _summed(pid, "sched", "nr_migrations")


MIGRATIONS: dict[str, float] = {}
"""Both nodes' threads' moves from one CPU to another per round trip, by topic."""

SWITCHES: dict[str, float] = {}
"""Context switches of both nodes per round trip, by topic (filled by ``round_trips``)."""


def round_trips(rospy, topic: str, msg_type, make, samples: int, warmup: int = 50,
                pids: tuple[int, ...] = ()) -> list[float]:  # fmt: skip
    got = threading.Event()
    sub = rospy.Subscriber(f"/pong_{topic}", msg_type, lambda _m: got.set(), tcp_nodelay=True)
    pub = rospy.Publisher(f"/ping_{topic}", msg_type, queue_size=10, tcp_nodelay=True)
    deadline = time.monotonic() + 20
    while (pub.get_num_connections() == 0 or sub.get_num_connections() == 0) and (
        time.monotonic() < deadline
    ):
        time.sleep(0.05)
    time.sleep(0.5)
    rtts = []
    switches = moves = 0
    for i in range(warmup + samples):
        if i == warmup:
            switches = sum(context_switches(pid) for pid in pids)
            moves = sum(migrations(pid) for pid in pids)
        got.clear()
        msg = make()
        t0 = time.perf_counter()
        pub.publish(msg)
        if not got.wait(2.0):
            raise RuntimeError(f"rospy {topic} ping {i} got no pong within 2 s")
        if i >= warmup:
            rtts.append(time.perf_counter() - t0)
    if pids and samples:
        SWITCHES[topic] = (sum(context_switches(pid) for pid in pids) - switches) / samples
        MIGRATIONS[topic] = (sum(migrations(pid) for pid in pids) - moves) / samples
    sub.unregister()
    pub.unregister()
    return rtts


def flood(rospy, child, kind: str, msg_type, msg, seconds: float) -> float:
    """Publish ``msg`` as fast as rospy takes it for ``seconds``; messages per second the
    child received."""
    pub = rospy.Publisher(f"/flood_{kind}", msg_type, queue_size=1000, tcp_nodelay=True)
    deadline = time.monotonic() + 20
    while pub.get_num_connections() == 0 and time.monotonic() < deadline:
        time.sleep(0.05)
    time.sleep(0.5)
    end = time.monotonic() + seconds
    while time.monotonic() < end:
        pub.publish(msg)
    time.sleep(1.0)
    child.stdin.write(kind + "\n")
    child.stdin.flush()
    counts = json.loads(child.stdout.readline())
    span = counts["last"] - counts["first"]
    pub.unregister()
    return (counts["n"] - 1) / span if span > 0 else 0.0


def main() -> int:
    parser = CommandParser(description=first_line(__doc__))
    parser.add_argument("--small", type=int, default=2000)
    parser.add_argument("--image", type=int, default=400)
    parser.add_argument("--seconds", type=float, default=4.0)
    parser.add_argument("--pong", action="store_true", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.pong:
        pong()
        return 0
    os.environ["ROS_MASTER_URI"] = f"http://127.0.0.1:{free_port()}"
    os.environ.setdefault("ROS_HOSTNAME", "127.0.0.1")
    os.environ.setdefault("ROS_LOG_DIR", "/tmp/bench_rospy_logs")
    port = os.environ["ROS_MASTER_URI"].rsplit(":", 1)[1]
    master = subprocess.Popen(
        ["rosmaster", "--core", "-p", port], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL
    )
    child = None
    try:
        import rospy
        from sensor_msgs.msg import Image
        from std_msgs.msg import UInt8MultiArray

        deadline = time.monotonic() + 20
        while time.monotonic() < deadline:
            with socket.socket() as sock:
                if sock.connect_ex(("127.0.0.1", int(port))) == 0:
                    break
            time.sleep(0.1)
        child = subprocess.Popen(
            [sys.executable, __file__, "--pong"], stdin=subprocess.PIPE, stdout=subprocess.PIPE,
            text=True,
        )  # fmt: skip
        assert child.stdout.readline().strip() == "ready"
        rospy.init_node("bench_ping", anonymous=True, disable_signals=True)
        small = bytes(64)
        frame = bytes(640 * 480 * 3)

        def make_image() -> Image:
            msg = Image(height=480, width=640, encoding="bgr8", step=1920, data=frame)
            msg.header.stamp = rospy.Time.now()
            return msg

        result = {
            "small_rtt_ms": percentiles_ms(round_trips(
                rospy, "small", UInt8MultiArray, lambda: UInt8MultiArray(data=small), args.small,
                pids=(os.getpid(), child.pid),
            )),
            "image_rtt_ms": percentiles_ms(
                round_trips(rospy, "image", Image, make_image, args.image)
            ),
        }  # fmt: skip
        result["images_per_s"] = flood(rospy, child, "image", Image, make_image(), args.seconds)
        result["small_per_s"] = flood(
            rospy, child, "small", UInt8MultiArray, UInt8MultiArray(data=small), args.seconds
        )
        result["small_switches_per_rtt"] = SWITCHES.get("small")
        result["small_migrations_per_rtt"] = MIGRATIONS.get("small")
        print(json.dumps(result), flush=True)
        return 0
    finally:
        if child is not None:
            child.stdin.close()
            child.wait(20)
        master.terminate()
        master.wait(10)


if __name__ == "__main__":
    raise SystemExit(main())
