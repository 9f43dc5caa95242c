"""bridge_tello: video latency (encode -> frame on Zenoh), command round trip, CPU with video.

Runs the real bridge (``python -m dronewrapper_bridge_tello``) against a Tello stand-in in
this process that speaks the SDK on a loopback address of its own: answers ``command``,
``streamon`` and reads at once, sends a state string at 10 Hz and H.264 video at 30 fps,
960x720, encoded with the simulated Tello's own encoder (libx264 through PyAV, zerolatency,
1460-byte datagrams). Each frame carries its index as a row of black and white blocks, read back
from the published Image, so the latency of every frame is known:

* video latency: encode start here -> the decoded Image sample arriving here over Zenoh (target
  p50 <= 60 ms, p99 <= 120 ms), and whether it grows: p50 of the first and the last fifth of
  the run (target: no growth);
* frames: sent, published, dropped by the newest-frame mailbox;
* command round trip: a PARAM_GET (``battery?``) service call through the bridge and back;
* CPU share of one core used by the bridge process while the video runs.

Both clocks are this machine's CLOCK_MONOTONIC. Run:
``.venv/bin/python -m bench.tello_video [--seconds S]``; writes bench/results/tello_video.json.
"""

from __future__ import annotations

import argparse
import random
import signal
import socket
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
from dronewrapper.msgs import registry
from dronewrapper.msgs.mavros import ParamGet
from dronewrapper.runtime import Node, ZenohOptions
from dronewrapper_sim.tello.video import H264Encoder, packetise

REPO = Path(__file__).resolve().parents[1]
W, H, FPS = 960, 720, 30.0
BITS, BLOCK = 20, 40  # frame index as 20 blocks of 40x40 px along the top
STATE = (
    "mid:-1;x:-100;y:-100;z:-100;mpry:-1,-1,-1;pitch:0;roll:0;yaw:0;vgx:0;vgy:0;vgz:0;"
    "templ:60;temph:62;tof:10;h:0;bat:87;baro:100.00;time:0;agx:0.00;agy:0.00;agz:-1000.00;\r\n"
)


def stamped_image(index: int) -> np.ndarray:
    """A moving gradient scene with ``index`` written as blocks along the top edge."""
    img = np.empty((H, W, 3), np.uint8)
    img[:] = ((np.arange(W) + 4 * index) % 256).astype(np.uint8)[None, :, None]
    img[:, :, 2] = (np.arange(H) // 3 % 256).astype(np.uint8)[:, None]
    for bit in range(BITS):
        value = 255 if (index >> bit) & 1 else 0
        img[0:BLOCK, bit * BLOCK : (bit + 1) * BLOCK] = value
    return img


def read_index(img: np.ndarray) -> int:
    """The index written by :func:`stamped_image` (block centres, thresholded)."""
    centre = BLOCK // 2
    index = 0
    for bit in range(BITS):
        if img[centre, bit * BLOCK + centre].mean() > 127:
            index |= 1 << bit
    return index


class TelloStandIn:
    """The Tello side: replies at once, a state string at 10 Hz, the video."""

    def __init__(self, address: str) -> None:
        self.address = address
        self.sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self.sock.bind((address, 8889))
        self.sock.settimeout(0.1)
        self.out = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self.client: tuple[str, int] | None = None
        self.streaming = threading.Event()
        self.sent_at: dict[int, float] = {}
        self.frames = 0
        self.stop = threading.Event()

    def command_loop(self) -> None:
        while not self.stop.is_set():
            try:
                data, source = self.sock.recvfrom(2048)
            except TimeoutError:
                continue
            text = data.decode("ascii", "replace").strip()
            if text.startswith("rc "):
                continue
            self.client = source
            if text == "streamon":
                self.streaming.set()
            reply = "87" if text.endswith("?") else "ok"
            self.sock.sendto(reply.encode(), source)

    def state_loop(self) -> None:
        while not self.stop.wait(0.1):
            if self.client is not None:
                self.out.sendto(STATE.encode(), (self.client[0], 8890))

    def video_loop(self, seconds: float) -> None:
        encoder = H264Encoder(W, H, FPS, 1500, 30)
        self.streaming.wait(30)
        start = time.monotonic()
        index = 0
        while not self.stop.is_set() and time.monotonic() - start < seconds:
            due = start + index / FPS
            delay = due - time.monotonic()
            if delay > 0:
                time.sleep(delay)
            image = stamped_image(index)
            self.sent_at[index] = time.monotonic()
            unit = encoder.encode(image)
            if unit and self.client is not None:
                for datagram in packetise(unit):
                    self.out.sendto(datagram, (self.client[0], 11111))
                self.frames += 1
            index += 1
        encoder.close()


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=60.0, help="length of the video run")
    args = parser.parse_args(argv)

    router = LoopbackRouter()
    if not router.start():
        print("router did not start", file=sys.stderr)
        return 1
    endpoint = router.endpoint
    address = f"127.{random.randint(10, 250)}.{random.randint(0, 255)}.{random.randint(2, 250)}"
    tello = TelloStandIn(address)
    threads = [
        threading.Thread(target=tello.command_loop, daemon=True),
        threading.Thread(target=tello.state_loop, daemon=True),
    ]
    for thread in threads:
        thread.start()
    bridge = subprocess.Popen(
        [sys.executable, "-m", "dronewrapper_bridge_tello", "--connect", endpoint,
         "--tello", address, "--local", address, "--log-level", "WARNING",
         "--set", "commander_lost_timeout=3600"],
        cwd=REPO,
    )  # fmt: skip
    node = Node(
        "bench", ZenohOptions(connect=[endpoint], namespace="drone", name="bench"),
        handle_signals=False,
    )  # fmt: skip
    arrivals: list[tuple[int, float]] = []

    def on_image(msg) -> None:
        now = time.monotonic()
        img = np.frombuffer(msg.data, np.uint8).reshape(msg.height, msg.width, 3)
        arrivals.append((read_index(img), now))

    node.subscribe(registry.IMAGE_RAW, on_image, camera="cam_frontal")
    results: dict[str, object] = {}
    try:
        video = threading.Thread(target=tello.video_loop, args=(args.seconds,), daemon=True)
        video.start()
        if not tello.streaming.wait(30):
            print("the bridge never sent streamon", file=sys.stderr)
            return 1
        time.sleep(2.0)
        c0, w0 = cpu_seconds(bridge.pid), time.monotonic()

        # command round trips while the video runs
        rtts = []
        for _ in range(50):
            t0 = time.monotonic()
            reply = node.call(registry.PARAM_GET, ParamGet(param_id="BATTERY"), timeout=5)
            if reply.success:
                rtts.append(time.monotonic() - t0)
            time.sleep(0.1)
        video.join(args.seconds + 30)
        time.sleep(1.0)
        cpu = (cpu_seconds(bridge.pid) - c0) / (time.monotonic() - w0)

        latencies = [
            (tello.sent_at[i], at - tello.sent_at[i]) for i, at in arrivals if i in tello.sent_at
        ]
        latencies.sort()
        values = [lat for _, lat in latencies]
        fifth = max(1, len(values) // 5)
        first, last = percentiles(values[:fifth]), percentiles(values[-fifth:])
        overall = percentiles(values)
        results = {
            "seconds": args.seconds,
            "video_latency": overall,
            "video_latency_first_fifth": first,
            "video_latency_last_fifth": last,
            "frames_sent": tello.frames,
            "frames_published_received": len(arrivals),
            "command_round_trip": percentiles(rtts),
            "bridge_cpu_share_one_core_with_video": round(cpu, 4),
        }
        print_table(
            "bridge_tello video 960x720 30 fps (ms)",
            ["figure", "p50", "p90", "p99", "max", "target"],
            [
                ["encode -> Image on Zenoh", *(overall.get(k, "-") for k in
                 ("p50_ms", "p90_ms", "p99_ms", "max_ms")), "p50 60, p99 120"],
                ["  first fifth", *(first.get(k, "-") for k in
                 ("p50_ms", "p90_ms", "p99_ms", "max_ms")), ""],
                ["  last fifth", *(last.get(k, "-") for k in
                 ("p50_ms", "p90_ms", "p99_ms", "max_ms")), "no growth"],
                ["command round trip (battery?)", *(percentiles(rtts).get(k, "-") for k in
                 ("p50_ms", "p90_ms", "p99_ms", "max_ms")), ""],
            ],
        )  # fmt: skip
        print(
            f"\nframes sent {tello.frames}, received {len(arrivals)}; "
            f"bridge CPU {cpu:.1%} of one core with video"
        )
        write_results("tello_video", results)
    finally:
        tello.stop.set()
        node.close()
        stop_process(bridge, signal.SIGTERM)
        router.stop(5)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
