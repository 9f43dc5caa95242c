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

import random
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

from bench import common
from bench.tello_standin import TelloStandIn
from dronewrapper.msgs import registry
from dronewrapper.msgs.mavros import ParamGet
from dronewrapper.runtime import Node, ZenohOptions
from dronewrapper.runtime.arguments import CommandParser, first_line
from dronewrapper_sim.tello.video import H264Encoder, packetise

REPO = Path(__file__).resolve().parents[1]
W, H, FPS = 960, 720, 30.0
BITS, BLOCK = 20, 40  # frame index as 20 blocks of 40x40 px along the top


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


class StampedVideo:
    """The stand-in's frames: each a :func:`stamped_image` of its index, encoded as the
    simulated Tello encodes, with the time (monotonic s) its encoding started."""

    def __init__(self) -> None:
        self.encoder = H264Encoder(W, H, FPS, 1500, 30)
        self.sent_at: dict[int, float] = {}

    def __call__(self, index: int) -> list[bytes]:
        image = stamped_image(index)
        self.sent_at[index] = time.monotonic()
        return packetise(self.encoder.encode(image))


def main(argv: list[str] | None = None) -> int:
    parser = CommandParser(description=first_line(__doc__))
    parser.add_argument("--seconds", type=float, default=60.0, help="length of the video run")
    args = parser.parse_args(argv)

    router = common.started_router()
    endpoint = router.endpoint
    address = f"127.{random.randint(10, 250)}.{random.randint(0, 255)}.{random.randint(2, 250)}"
    video = StampedVideo()
    tello = TelloStandIn(address, video, FPS)
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
        if not tello.streaming.wait(30):
            print("the bridge never sent streamon", file=sys.stderr)
            return 1
        end = time.monotonic() + args.seconds
        time.sleep(2.0)
        c0, w0 = common.cpu_seconds(bridge.pid), time.monotonic()

        # command round trips while the video runs
        rtts = []
        for _ in range(50):
            t0 = time.monotonic()
            reply = node.call(registry.PARAM_GET, ParamGet(param_id="BATTERY"), timeout=5)
            if reply.success:
                rtts.append(time.monotonic() - t0)
            time.sleep(0.1)
        time.sleep(max(0.0, end - time.monotonic()))
        cpu = (common.cpu_seconds(bridge.pid) - c0) / (time.monotonic() - w0)

        latencies = [
            (video.sent_at[i], at - video.sent_at[i]) for i, at in arrivals if i in video.sent_at
        ]
        latencies.sort()
        values = [lat for _, lat in latencies]
        fifth = max(1, len(values) // 5)
        first, last = common.percentiles(values[:fifth]), common.percentiles(values[-fifth:])
        overall = common.percentiles(values)
        results = {
            "seconds": args.seconds,
            "video_latency": overall,
            "video_latency_first_fifth": first,
            "video_latency_last_fifth": last,
            "frames_sent": tello.frames,
            "frames_published_received": len(arrivals),
            "command_round_trip": common.percentiles(rtts),
            "bridge_cpu_share_one_core_with_video": round(cpu, 4),
        }
        common.print_table(
            "bridge_tello video 960x720 30 fps (ms)",
            ["figure", "p50", "p90", "p99", "max", "target"],
            [
                ["encode -> Image on Zenoh", *(overall.get(k, "-") for k in
                 ("p50_ms", "p90_ms", "p99_ms", "max_ms")), "p50 60, p99 120"],
                ["  first fifth", *(first.get(k, "-") for k in
                 ("p50_ms", "p90_ms", "p99_ms", "max_ms")), ""],
                ["  last fifth", *(last.get(k, "-") for k in
                 ("p50_ms", "p90_ms", "p99_ms", "max_ms")), "no growth"],
                ["command round trip (battery?)", *(common.percentiles(rtts).get(k, "-") for k in
                 ("p50_ms", "p90_ms", "p99_ms", "max_ms")), ""],
            ],
        )  # fmt: skip
        print(
            f"\nframes sent {tello.frames}, received {len(arrivals)}; "
            f"bridge CPU {cpu:.1%} of one core with video"
        )
        common.write_results("tello_video", results)
    finally:
        tello.close()
        video.encoder.close()
        node.close()
        common.stop_process(bridge, signal.SIGTERM)
        router.stop(5)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
