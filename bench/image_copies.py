"""Images between processes against the raw Zenoh floor: which copies cost what, in one run.

A 640x480 bgr8 frame makes a round trip to an echo in another process (peer to peer, shared
memory on) that copies the payload out (``ZBytes.to_bytes``, what every Python subscriber must
do) and puts it back as plain bytes, so only the way the frame is sent differs:

* ``raw bytes (floor)``: the pixels already in a ``bytes`` object, put as they are (Zenoh
  copies them once into shared memory);
* ``before, ...``: an Image message through a Publisher without the shared-memory writer
  (MessagePack writes a new buffer, Zenoh copies it into shared memory: one copy more than the
  floor), around ``bytes``, and around a rendered array's ``tobytes()`` (what the simulator's
  camera did: two more);
* ``now, ...``: the runtime's Publisher today (:mod:`dronewrapper.runtime.shm_put`: the header
  encoded alone, header and pixels written once into a ``ZShmMut``), around ``bytes`` (as many
  copies as the floor) and around a memoryview of the array (what the simulator's camera does:
  the binding's ``ZShmMut`` takes only ``bytes``, so the pixels are copied to ``bytes`` first).

Also the receiving side, timed in the pong callback: ``to_bytes`` (the forced copy out of shared
memory: ``ZBytes`` has no buffer protocol) and our typed decode (zero-copy: ``Image.data`` is a
view of those bytes).

Run: ``python -m bench.image_copies [--samples 400]``; writes results/image_copies.json.
"""

from __future__ import annotations

import argparse
import subprocess
import sys
import threading
import time

import numpy as np
import zenoh

from bench.common import percentiles, print_table, write_results
from dronewrapper.msgs import Header, Image, codec, registry
from dronewrapper.runtime import Node, ZenohOptions
from dronewrapper.runtime.arguments import CommandParser, first_line
from dronewrapper.runtime.node import Publisher
from dronewrapper_compose.ports import free_port

PING = "bench_copies/ping"
PONG = "bench_copies/pong"
BLOCK = {"congestion_control": zenoh.CongestionControl.BLOCK}
HEIGHT, WIDTH = 480, 640
PIXELS = np.random.default_rng(0).integers(0, 255, (HEIGHT, WIDTH, 3), dtype=np.uint8)
PIXEL_BYTES = PIXELS.tobytes()


def image(data) -> Image:
    return Image(header=Header.now("cam_frontal"), height=HEIGHT, width=WIDTH, encoding="bgr8",
                 step=WIDTH * 3, data=data)  # fmt: skip


def echo(options: ZenohOptions) -> None:
    """Child: copy each ping out and put it back as bytes, until stdin closes."""
    with Node("bench_copies_echo", options, handle_signals=False, linger=0.0) as node:
        pub = node.session.declare_publisher(PONG, **BLOCK)
        node.session.declare_subscriber(PING, lambda s: pub.put(s.payload.to_bytes()))
        print("ready", flush=True)
        for _ in sys.stdin:
            pass


def round_trips(
    node: Node, send, samples: int, receive: dict[str, list[float]], warmup: int = 50
) -> list[float]:
    """Round trips (s); ``receive`` gains the time of each pong's copy out of shared memory
    and of its typed decode (when it is a message)."""
    got = threading.Event()
    decoder = codec.decoder(Image)

    def on_pong(sample: zenoh.Sample) -> None:
        t0 = time.perf_counter()
        data = sample.payload.to_bytes()
        t1 = time.perf_counter()
        receive["to_bytes (copy out of SHM)"].append(t1 - t0)
        if len(data) != len(PIXEL_BYTES):
            decoder.decode(data)
            receive["typed decode (zero-copy view)"].append(time.perf_counter() - t1)
        got.set()

    sub = node.session.declare_subscriber(PONG, on_pong)
    rtts = []
    for i in range(warmup + samples):
        got.clear()
        t0 = time.perf_counter()
        send()
        if not got.wait(2.0):
            raise RuntimeError(f"ping {i} got no pong within 2 s")
        if i >= warmup:
            rtts.append(time.perf_counter() - t0)
    sub.undeclare()
    return rtts


def run(samples: int, interleave: int = 8, ways: tuple[str, ...] = ()) -> dict[str, object]:
    """Round trips of each way of sending (all, or the named ``ways``), interleaved."""
    endpoint = f"tcp/127.0.0.1:{free_port('tcp')}"
    child = subprocess.Popen(
        [sys.executable, "-m", "bench.image_copies", "--echo", endpoint],
        stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True,
    )  # fmt: skip
    try:
        if child.stdout.readline().strip() != "ready":
            raise RuntimeError("the echo process did not start")
        options = ZenohOptions(mode="peer", connect=[endpoint])
        with Node("bench_copies_ping", options, handle_signals=False, linger=0.0) as node:
            raw_pub = node.session.declare_publisher(PING, **BLOCK)
            now = node.publisher(registry.IMAGE_RAW, key=PING, qos=BLOCK)
            before = Publisher(node.session, PING, Image, **BLOCK)  # no shared-memory writer
            view = memoryview(PIXELS).cast("B")
            every = {
                "raw bytes (floor)": lambda: raw_pub.put(PIXEL_BYTES),
                "before, bytes": lambda: before.put(image(PIXEL_BYTES)),
                "before, numpy + tobytes": lambda: before.put(image(PIXELS.tobytes())),
                "now, bytes": lambda: now.put(image(PIXEL_BYTES)),
                "now, numpy view": lambda: now.put(image(view)),
            }
            chosen = {k: v for k, v in every.items() if not ways or k in ways}
            time.sleep(1.0)
            rtts: dict[str, list[float]] = {name: [] for name in chosen}
            receive: dict[str, list[float]] = {
                "to_bytes (copy out of SHM)": [],
                "typed decode (zero-copy view)": [],
            }
            for _ in range(interleave):  # rounds, so a slow spell of the machine hits all
                for name, send in chosen.items():
                    rtts[name] += round_trips(node, send, samples // interleave, receive)
    finally:
        child.stdin.close()
        child.wait(20)
    return {
        "rtt": {k: percentiles(v) for k, v in rtts.items()},
        "receive": {k: percentiles(v) for k, v in receive.items()},
    }


def main(argv: list[str] | None = None) -> int:
    parser = CommandParser(description=first_line(__doc__))
    parser.add_argument("--samples", type=int, default=400)
    parser.add_argument("--echo", help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.echo:
        echo(ZenohOptions(mode="peer", listen=[args.echo]))
        return 0
    result = run(args.samples)
    floor = result["rtt"]["raw bytes (floor)"]["p50_ms"]
    rows = [[name, r["p50_ms"], r["p99_ms"], r["p50_ms"] - floor]
            for name, r in result["rtt"].items()]  # fmt: skip
    print_table(
        "640x480 bgr8 round trip, peer to peer, shared memory on (ms; echo copies out and puts "
        "back bytes)",
        ["sent as", "RTT p50", "RTT p99", "over the floor"],
        rows,
    )
    recv = result["receive"]
    print_table(
        "receiving one frame, in the subscriber callback (ms)",
        ["step", "p50", "p99"],
        [[k, v["p50_ms"], v["p99_ms"]] for k, v in recv.items()],
    )
    write_results("image_copies", result)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
