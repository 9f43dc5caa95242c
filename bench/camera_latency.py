"""camera_victure: capture-to-Zenoh latency and CPU against the camera's targets.

The camera service runs as its own process on a loopback router with the test pattern as its
"camera" at 30 fps, 640x480 and 1280x720, publishing raw bgr8 or JPEG only. A subscriber here
takes ``arrival - header.stamp`` for every frame; the stamp is taken when the pattern frame is
complete, so this is the latency the service adds over the capture itself (hand-over from the
reading thread, message encoding, JPEG encoding when on, Zenoh, the subscriber's decode).
CPU: the service process's user+system time over the run, as a share of one core, and the
pattern's own drawing cost measured here (the part a real camera would not cost). JPEG encode
cost (quality 80) is measured alone too. Target: <= 3 ms added, raw.

Run: ``python -m bench.camera_latency [--duration 10]``. Writes bench/results/camera_latency.json.
"""

from __future__ import annotations

import statistics
import subprocess
import sys
import time
from pathlib import Path

from bench.common import (
    call_times_ms,
    cpu_seconds,
    percentiles,
    print_table,
    started_router,
    write_results,
)
from dronewrapper.images import bgr_to_image, bgr_to_jpeg
from dronewrapper.msgs import registry
from dronewrapper.runtime import Node, ZenohOptions
from dronewrapper.runtime.arguments import CommandParser, first_line
from dronewrapper_camera_victure.pattern import render_pattern

REPO = Path(__file__).resolve().parents[1]
SIZES = ((640, 480), (1280, 720))
FPS = 30


def median_ms(fn, runs: int = 200) -> float:
    """Median wall time of ``fn()`` (ms) over ``runs`` calls."""
    return statistics.median(call_times_ms(fn, runs))


def one_run(endpoint: str, width: int, height: int, jpeg: bool, duration: float) -> dict:
    """Latency and CPU of the camera process for one size and output."""
    sets = [
        "source=pattern",
        f"width={width}",
        f"height={height}",
        f"fps={FPS}",
        f"jpeg={str(jpeg).lower()}",
        f"publish_raw={str(not jpeg).lower()}",
    ]
    argv = [sys.executable, "-m", "dronewrapper_camera_victure", "--connect", endpoint]
    argv += [a for s in sets for a in ("--set", s)]
    latencies: list[float] = []
    options = ZenohOptions(mode="peer", connect=[endpoint], name="bench")
    with Node("bench", options, handle_signals=False) as node:
        topic = registry.IMAGE_COMPRESSED if jpeg else registry.IMAGE_RAW
        node.subscribe(topic, lambda m: latencies.append(time.time() - m.header.stamp),
                       camera="cam_frontal")  # fmt: skip
        proc = subprocess.Popen(argv, cwd=REPO, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
        try:
            deadline = time.monotonic() + 30
            while not latencies and time.monotonic() < deadline and proc.poll() is None:
                time.sleep(0.05)
            if not latencies:
                raise RuntimeError(f"no frames from the camera: {proc.stderr.read().decode()}")
            time.sleep(1.0)  # warm-up
            latencies.clear()
            cpu0, t0 = cpu_seconds(proc.pid), time.monotonic()
            time.sleep(duration)
            cpu = (cpu_seconds(proc.pid) - cpu0) / (time.monotonic() - t0)
            frames = len(latencies)
            values = list(latencies)
        finally:
            proc.terminate()
            proc.wait(15)
    stats = percentiles(values)
    return {
        "size": f"{width}x{height}",
        "output": "jpeg" if jpeg else "raw",
        "fps_received": frames / duration,
        "cpu_core_share": cpu,
        **stats,
    }


def main(argv: list[str] | None = None) -> int:
    parser = CommandParser(description=first_line(__doc__))
    parser.add_argument("--duration", type=float, default=10.0, help="seconds per run")
    args = parser.parse_args(argv)
    router = started_router()
    endpoint = router.endpoint
    runs, costs = [], []
    try:
        for width, height in SIZES:
            frame = render_pattern(width, height, 1, time.time())
            costs.append(
                {
                    "size": f"{width}x{height}",
                    "pattern_draw_ms": median_ms(
                        lambda w=width, h=height: render_pattern(w, h, 7, 0.0)
                    ),
                    "jpeg_encode_q80_ms": median_ms(
                        lambda f=frame: bgr_to_jpeg(f, 1.0, "cam_frontal", 0, 80)
                    ),
                    "raw_message_ms": median_ms(
                        lambda f=frame: bgr_to_image(f, 1.0, "cam_frontal")
                    ),
                }
            )
            for jpeg in (False, True):
                runs.append(one_run(endpoint, width, height, jpeg, args.duration))
    finally:
        router.stop(10)
    print_table(
        f"capture-to-Zenoh latency, test pattern at {FPS} fps ({args.duration:g} s each)",
        ["size", "output", "fps", "p50 ms", "p90 ms", "p99 ms", "max ms", "CPU (core)"],
        [
            [r["size"], r["output"], r["fps_received"], r["p50_ms"], r["p90_ms"], r["p99_ms"],
             r["max_ms"], r["cpu_core_share"]]
            for r in runs
        ],
    )  # fmt: skip
    print_table(
        "costs in this process (median ms)",
        ["size", "pattern draw", "JPEG encode q80", "raw message"],
        [[c["size"], c["pattern_draw_ms"], c["jpeg_encode_q80_ms"], c["raw_message_ms"]]
         for c in costs],
    )  # fmt: skip
    write_results("camera_latency", {"fps": FPS, "runs": runs, "costs": costs})
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
