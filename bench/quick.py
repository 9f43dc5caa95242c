"""The self-benchmark (``dronewrapper bench --quick``): this computer's detector speed, image
transport floor and follow-person latency budget in about a minute, and detector settings that
meet a latency target.

1. YOLOX ``detect()`` (``--model``, default YOLOX-Nano) on a 640x480 photo with the execution
   providers asked for (``--providers``, as the perception config's ``providers``), at each
   input size the model accepts (a static-shape model: its own size only).
2. A 640x480 image's round trip to another process: plain Zenoh (the floor) and through our
   runtime, in the same run.
3. The follow-person graph (simulator, bridge, perception with YOLOX on the CPU, controller)
   for ``--seconds``: the latency budget stage by stage and the middleware's share.
4. The suggestion: the largest input and the detector rate that meet ``--target-ms``
   (glass-to-setpoint p50) within ``--cpu-budget`` cores (see :mod:`bench.suggest`).

    python -m bench.quick [--target-ms 60] [--providers auto] [--model M.onnx] [--seconds 15]
"""

from __future__ import annotations

import argparse
import logging
import math
import sys
import time
from pathlib import Path

import cv2
import numpy as np

from bench.common import percentiles, print_table, write_results
from bench.suggest import DetectorSpeed, suggest
from dronewrapper.runtime.arguments import CommandParser

DETECTOR_RUNS = 30
SIZES = (416, 320, 256)
MODEL = Path(__file__).resolve().parents[1] / "assets" / "models" / "yolox_nano.onnx"


def detector_speeds(
    providers: list[str], threads: int, model: Path
) -> tuple[list[DetectorSpeed], list[str]]:
    """YOLOX ``detect()`` time at each input size the model takes; the providers it ran on."""
    from bench.latency_budget import ASSETS
    from dronewrapper_perception.yolox import YoloxDetector

    photo = cv2.imread(str(ASSETS / "images" / "vtest_f0550.png"))
    frame = cv2.resize(photo, (640, 480)) if photo is not None else np.zeros((480, 640, 3), "u1")
    first = YoloxDetector(model, providers=providers or None, threads=threads)
    detectors = [first]
    if first.input_size == SIZES[0]:  # the model may fix its input size: then only that one
        for size in SIZES[1:]:
            other = YoloxDetector(model, input_size=size, threads=threads,
                                  providers=providers or None)  # fmt: skip
            if other.input_size != size:
                break
            detectors.append(other)
    speeds = []
    for detector in detectors:
        times = []
        for k in range(DETECTOR_RUNS + 3):
            t0 = time.perf_counter()
            detector.detect(frame)
            if k >= 3:
                times.append(time.perf_counter() - t0)
        p = percentiles(times)
        speeds.append(DetectorSpeed(detector.input_size, p["p50_ms"] / 1e3, p["p99_ms"] / 1e3))
    return speeds, first.providers


def transport_floor(samples: int) -> dict[str, dict[str, float]]:
    """640x480 round trips: plain Zenoh vs our runtime (see bench.image_copies)."""
    import bench.image_copies as copies

    result = copies.run(samples, interleave=2, ways=("raw bytes (floor)", "now, numpy view"))
    return result["rtt"]


def main(argv: list[str] | None = None) -> int:
    parser = CommandParser(
        prog="dronewrapper bench --quick",
        description="This computer's detector speed, image transport floor and latency budget, "
        "and detector settings that meet a latency target.",
    )
    parser.add_argument("--quick", action="store_true", help=argparse.SUPPRESS)
    parser.add_argument("--target-ms", type=float, default=60.0,
                        help="glass-to-setpoint p50 to meet (ms, default 60)")  # fmt: skip
    parser.add_argument("--providers", default="cpu",
                        help="execution providers for the detector test: cpu, cuda, tensorrt, "
                             "auto (comma-separated)")  # fmt: skip
    parser.add_argument("--threads", type=int, default=2, help="CPU threads per inference")
    parser.add_argument("--model", type=Path, default=MODEL,
                        help="YOLOX ONNX model to time (e.g. yolox_s.onnx)")  # fmt: skip
    parser.add_argument("--cpu-budget", type=float, default=1.0,
                        help="cores the detector may use (default 1)")  # fmt: skip
    parser.add_argument("--camera-fps", type=float, default=30.0)
    parser.add_argument("--seconds", type=float, default=15.0, help="graph measurement (s)")
    parser.add_argument("--samples", type=int, default=200, help="image round trips per way")
    parser.add_argument("--skip-graph", action="store_true",
                        help="no graph run: estimate from the transport alone")  # fmt: skip
    args = parser.parse_args(argv)
    for name in ("target_ms", "cpu_budget", "camera_fps", "seconds"):
        value = getattr(args, name)
        if not (math.isfinite(value) and value > 0):
            parser.error(f"--{name.replace('_', '-')} must be positive")
    logging.basicConfig(level=logging.WARNING, format="%(levelname)s %(name)s: %(message)s")
    started = time.monotonic()
    providers = [p.strip() for p in args.providers.split(",") if p.strip()]

    print("1/3 detector speed ...", flush=True)
    speeds, active = detector_speeds(providers, args.threads, args.model)
    print_table(
        f"{args.model.name} detect() on 640x480, {args.threads} CPU threads, on "
        f"{', '.join(active)} (ms)",
        ["input px", "p50", "p99"],
        [[s.input_size, s.p50_s * 1e3, s.p99_s * 1e3] for s in speeds],
    )

    print("\n2/3 image transport ...", flush=True)
    rtt = transport_floor(args.samples)
    floor, ours = rtt["raw bytes (floor)"], rtt["now, numpy view"]
    print_table(
        "640x480 image round trip between two processes (ms)",
        ["path", "p50", "p99"],
        [["plain Zenoh (floor)", floor["p50_ms"], floor["p99_ms"]],
         ["our runtime", ours["p50_ms"], ours["p99_ms"]]],
    )  # fmt: skip

    result: dict[str, object] = {
        "providers": active,
        "model": str(args.model),
        "detector": [vars(s) for s in speeds],
        "transport": rtt,
    }
    if args.skip_graph:
        render_s = 0.005
        mw_p50 = ours["p50_ms"] / 1e3 * 2  # frame one way + detections + setpoint, roughly
        mw_p99 = ours["p99_ms"] / 1e3 * 2
        print("\n3/3 latency budget: skipped (--skip-graph); middleware estimated from transport")
    else:
        from bench.latency_budget import measure, print_budget

        print(f"\n3/3 follow-person graph for {args.seconds:.0f} s (starting it takes a moment)"
              " ...", flush=True)  # fmt: skip
        budget = measure("person", args.seconds, frames=30)
        print_budget("person", budget)
        result["budget"] = budget
        stages = budget["stages"]
        render_s = stages["render"]["p50_ms"] / 1e3
        mw_p50 = stages["middleware"]["p50_ms"] / 1e3
        mw_p99 = stages["middleware"]["p99_ms"] / 1e3
        if not (math.isfinite(mw_p50) and math.isfinite(mw_p99)):
            print("no frame was measured through the graph; see its log", file=sys.stderr)
            return 1

    advice = suggest(args.target_ms, speeds, render_s=render_s, middleware_p50_s=mw_p50,
                     middleware_p99_s=mw_p99, camera_fps=args.camera_fps,
                     cpu_budget=args.cpu_budget)  # fmt: skip
    print_table(
        f"settings against a {args.target_ms:.0f} ms target (estimates, ms)",
        ["input px", "detector fps", "p50", "p99", "cores"],
        [[c.input_size, round(c.fps, 1), c.p50_ms, c.p99_ms, round(c.cpu_cores, 2)]
         for c in advice.candidates],
    )  # fmt: skip
    verdict = "suggested" if advice.meets_target else "target missed"
    print(f"\n{verdict}: {advice.reason}")
    if len(speeds) == 1:
        print(f"  (this model's input is fixed at {speeds[0].input_size} px; a dynamic-shape "
              "export allows smaller inputs)")  # fmt: skip
    print(f"  perception: input_size={advice.best.input_size} "
          f"max_rate_hz={advice.best.fps:.0f} (a graph's detect_rate_hz), "
          f"providers={args.providers}")  # fmt: skip
    result["suggestion"] = {"meets_target": advice.meets_target, "reason": advice.reason,
                            **vars(advice.best)}  # fmt: skip
    print(f"\nquick bench took {time.monotonic() - started:.0f} s")
    write_results("quick", result)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
