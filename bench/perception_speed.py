"""Perception speed, latency and identity benchmarks against perception's targets.

1. Colour filter ms/frame at 640x480 on one core (target <= 3 ms).
2. YOLOX-Nano ms/frame with 2 threads, whole ``detect()`` and inference alone (target <= 20 ms);
   HOG for comparison.
3. Frame-to-detections latency through Zenoh at 30 fps: a publisher process sends 640x480 bgr8
   frames stamped with the wall clock, the perception process (its own OS process) detects, a
   subscriber here takes ``arrival - frame stamp``: p50/p99, and whether it grows (p50 of the
   last fifth vs the first fifth, and a fitted slope in ms/min).
4. ID switches per crossing scenario (simulator renderer, YOLOX, each tracker): how often the
   target's track id changes while it is seen, and frames where the follower picks someone else.

Run: ``python -m bench.perception_speed [--duration 300] [--latency-detector yolox]``;
``--duration`` is the latency run in seconds (60 by default; 300 for the full five minutes).
Writes bench/results/perception.json.
"""

from __future__ import annotations

import argparse
import json
import math
import statistics
import subprocess
import sys
import time
from pathlib import Path

import cv2
import numpy as np

from bench.common import (
    RESULTS,
    LoopbackRouter,
    call_times_ms,
    percentiles,
    print_table,
    stop_process,
    write_results,
)
from dronewrapper.runtime.arguments import CommandParser

REPO = Path(__file__).resolve().parents[1]
ASSETS = REPO / "assets"
YOLOX_NANO = ASSETS / "models" / "yolox_nano.onnx"
VTEST = ASSETS / "images" / "vtest_f0550.png"


def median_ms(fn, runs: int, warmup: int = 5) -> tuple[float, float, float]:
    """Median, p90 and minimum of ``fn()`` wall time in ms (the minimum is the figure least
    disturbed by other processes on a shared machine)."""
    times = call_times_ms(fn, runs, warmup)
    return statistics.median(times), float(np.percentile(times, 90)), min(times)


def colour_frame() -> np.ndarray:
    rng = np.random.default_rng(0)
    img = np.clip(rng.normal(110, 25, (480, 640, 3)), 0, 255).astype(np.uint8)
    cv2.circle(img, (400, 200), 35, (20, 20, 220), -1)
    cv2.circle(img, (100, 380), 10, (30, 30, 200), -1)
    return img


def bench_compute(runs: int) -> dict[str, object]:
    from dronewrapper_perception.color_filter import RED, detect_color
    from dronewrapper_perception.config import Config
    from dronewrapper_perception.hog import HogDetector
    from dronewrapper_perception.yolox import YoloxDetector, letterbox

    cv2.setNumThreads(1)
    frame = colour_frame()
    assert detect_color(frame, RED), "benchmark frame must contain the red disc"
    scale = Config().color_scale  # the service's default analysis scale
    colour = median_ms(lambda: detect_color(frame, RED, scale=scale), runs * 3)
    colour_full = median_ms(lambda: detect_color(frame, RED, scale=1.0), runs * 3)
    cv2.setNumThreads(0)
    people = cv2.imread(str(VTEST))
    detector = YoloxDetector(YOLOX_NANO, threads=2)
    yolox = median_ms(lambda: detector.detect(people), runs)
    canvas, _ = letterbox(people, detector.input_size)
    blob = np.ascontiguousarray(canvas.transpose(2, 0, 1)[None], dtype=np.float32)
    inference = median_ms(lambda: detector.session.run(None, {detector.input_name: blob}), runs)
    one_thread = YoloxDetector(YOLOX_NANO, threads=1)
    yolox_1t = median_ms(lambda: one_thread.detect(people), runs)
    hog_detector = HogDetector()
    hog = median_ms(lambda: hog_detector.detect(people), max(5, runs // 5), warmup=1)
    rows = [
        (f"colour detect_color 640x480, 1 core (default scale {scale:g})", *colour, 3.0),
        ("colour detect_color 640x480, 1 core, full resolution", *colour_full, None),
        ("YOLOX-Nano detect() 768x576, 2 threads", *yolox, 20.0),
        ("YOLOX-Nano inference only, 2 threads", *inference, 20.0),
        ("YOLOX-Nano detect(), 1 thread", *yolox_1t, None),
        ("HOG people 768x576 (downscaled to 640)", *hog, None),
    ]
    print_table(
        "Compute per frame (median over runs)",
        ["what", "median ms", "p90 ms", "min ms", "target ms", "median meets"],
        [
            (n, m, p, lo, t if t else "-", ("yes" if m <= t else "NO") if t else "-")
            for n, m, p, lo, t in rows
        ],
    )
    return {
        name: {"median_ms": m, "p90_ms": p, "min_ms": lo, "target_ms": t}
        for name, m, p, lo, t in rows
    }


# ---------------------------------------------------------------- latency through Zenoh


def publisher_main(endpoint: str, fps: float, duration: float) -> int:
    """The camera stand-in process: 640x480 frames with a moving red disc at ``fps``."""
    from dronewrapper.images import bgr_to_image
    from dronewrapper.msgs import registry
    from dronewrapper.runtime import Node, Ratekeeper, ZenohOptions

    base = colour_frame()
    options = ZenohOptions(mode="peer", connect=[endpoint], name="bench_camera")
    with Node("bench_camera", options) as node:
        pub = node.publisher(registry.IMAGE_RAW, camera="cam_frontal")
        rate = Ratekeeper(fps, stop=node.stop_event)
        end = time.monotonic() + duration
        k = 0
        while time.monotonic() < end and rate.sleep():
            frame = base.copy()
            cv2.circle(frame, (200 + (k * 3) % 300, 240), 30, (20, 20, 220), -1)
            pub.put(bgr_to_image(frame, time.time(), "cam_frontal", k))
            k += 1
    return 0


def bench_latency(duration: float, fps: float, detector: str) -> dict[str, object]:
    from dronewrapper.msgs import Detections, registry
    from dronewrapper.runtime import Node, ZenohOptions

    router = LoopbackRouter()
    router.start()
    endpoint = router.endpoint
    settings = ["--set", f"detector={detector}", "--set", "stats_period_s=30"]
    if detector == "yolox":
        settings += ["--set", f"model_path={YOLOX_NANO}"]
    perception = subprocess.Popen(
        [sys.executable, "-m", "dronewrapper_perception", "--connect", endpoint, *settings],
        cwd=REPO,
    )
    samples: list[tuple[float, float]] = []  # (arrival time, latency s)
    options = ZenohOptions(mode="peer", connect=[endpoint], name="bench_sink")
    publisher = None
    try:
        with Node("bench_sink", options, handle_signals=False) as node:

            def on_detections(msg: Detections) -> None:
                now = time.time()
                samples.append((now, now - msg.header.stamp))

            node.subscribe(registry.DETECTIONS, on_detections)
            time.sleep(3.0)  # perception start-up (model load, warm-up)
            publisher = subprocess.Popen(
                [sys.executable, "-m", "bench.perception_speed", "--role", "publisher",
                 "--endpoint", endpoint, "--fps", str(fps), "--duration", str(duration)],
                cwd=REPO,
            )  # fmt: skip
            publisher.wait(duration + 60)
            time.sleep(1.0)
    finally:
        if publisher is not None and publisher.poll() is None:
            publisher.kill()
        stop_process(perception, timeout_s=15)
        router.stop(10)
    if len(samples) < 10:
        raise RuntimeError(f"only {len(samples)} Detections received")
    arrivals = np.array([a for a, _ in samples])
    latencies = np.array([lat for _, lat in samples])
    fifth = max(1, len(latencies) // 5)
    first, last = latencies[:fifth], latencies[-fifth:]
    slope = float(np.polyfit(arrivals - arrivals[0], latencies * 1e3, 1)[0]) * 60.0
    first_p50, last_p50 = float(np.median(first) * 1e3), float(np.median(last) * 1e3)
    grows = last_p50 > first_p50 + max(5.0, 0.5 * first_p50)
    span = arrivals[-1] - arrivals[0]
    stats = percentiles(latencies)
    result = {
        "detector": detector,
        "fps_sent": fps,
        "duration_s": duration,
        "detections_received": len(samples),
        "processed_fps": (len(samples) - 1) / span if span > 0 else 0.0,
        **stats,
        "first_fifth_p50_ms": first_p50,
        "last_fifth_p50_ms": last_p50,
        "slope_ms_per_min": slope,
        "grows": bool(grows),
    }
    print_table(
        f"Frame-to-detections latency through Zenoh ({detector}, {fps:g} fps, {duration:g} s)",
        ["n", "out fps", "p50 ms", "p99 ms", "max ms", "first p50", "last p50", "ms/min", "grows"],
        [(len(samples), result["processed_fps"], stats["p50_ms"], stats["p99_ms"],
          stats["max_ms"], first_p50, last_p50, slope, "yes" if grows else "no")],
    )  # fmt: skip
    return result


# ---------------------------------------------------------------- ID switches in the sim


def bench_crossings(seconds: float, fps: float) -> list[dict[str, object]]:
    from dronewrapper.runtime.config import load_config
    from dronewrapper_perception.config import Config
    from dronewrapper_perception.pipeline import Pipeline
    from dronewrapper_sim.evaluation.boxes import owner, person_boxes
    from dronewrapper_sim.render.camera import FRONTAL, PinholeCamera, yaw_to_quat
    from dronewrapper_sim.render.renderer import Renderer
    from dronewrapper_sim.world.scenario import load_scenario
    from dronewrapper_sim.world.world import World

    vehicle = np.array([0.0, 0.0, 1.5])
    quat = yaw_to_quat(0.0)

    rows = []
    for scenario in ("people_crossing_front", "people_crossing_behind"):
        for look in ("procedural", "sprites"):
            for tracker in ("kalman", "paper"):
                spec = load_scenario(scenario)
                world = World(spec)
                camera = PinholeCamera(
                    spec.camera.width, spec.camera.height, math.radians(spec.camera.hfov_deg)
                )
                renderer = Renderer(
                    world, camera, ASSETS / "sprites" if look == "sprites" else None
                )
                config = load_config(
                    Config,
                    data={"detector": "yolox", "model_path": str(YOLOX_NANO), "tracker": tracker},
                )
                pipeline = Pipeline(config)
                switches, wrong, seen, previous = 0, 0, 0, None
                for _ in range(int(seconds * fps)):
                    image = renderer.render(FRONTAL, vehicle, quat)
                    result = pipeline.process(image, world.time_s)
                    people = person_boxes(world, camera, vehicle, quat)
                    owners = [owner(d.box_xyxy, people) for d in result.detections]
                    track = next(
                        (
                            t
                            for t, o in zip(result.tracking.track_ids, owners, strict=True)
                            if o == "target"
                        ),
                        None,
                    )
                    if track is not None:
                        seen += 1
                        if previous is not None and track != previous:
                            switches += 1
                        previous = track
                    index = result.tracking.target_index
                    if index is not None and owners[index] not in ("target", None):
                        wrong += 1
                    world.step(1.0 / fps)
                rows.append(
                    {
                        "scenario": scenario,
                        "people": look,
                        "tracker": tracker,
                        "frames": int(seconds * fps),
                        "target_seen_frames": seen,
                        "id_switches": switches,
                        "frames_following_someone_else": wrong,
                    }
                )
    print_table(
        f"ID switches of the target, {seconds:g} s at {fps:g} fps (YOLOX-Nano, 640x480)",
        ["scenario", "people", "tracker", "frames", "target seen", "id switches", "wrong target"],
        [(r["scenario"], r["people"], r["tracker"], r["frames"], r["target_seen_frames"],
          r["id_switches"], r["frames_following_someone_else"]) for r in rows],
    )  # fmt: skip
    return rows


def previous_results() -> dict[str, object]:
    """The sections of the last results file (without its machine facts), or {}."""
    path = RESULTS / "perception.json"
    try:
        data = json.loads(path.read_text())
    except (OSError, ValueError):
        return {}
    data.pop("machine", None)
    return data if isinstance(data, dict) else {}


def main(argv: list[str] | None = None) -> int:
    parser = CommandParser(prog="bench.perception_speed", description=__doc__)
    parser.add_argument("--duration", type=float, default=60.0, help="latency run, s")
    parser.add_argument("--fps", type=float, default=30.0)
    parser.add_argument("--latency-detector", default="color", choices=("color", "yolox", "hog"))
    parser.add_argument("--runs", type=int, default=100, help="timed runs per compute figure")
    parser.add_argument("--crossing-seconds", type=float, default=12.0)
    parser.add_argument("--skip", nargs="*", default=[], choices=("compute", "latency", "crossing"))
    parser.add_argument("--role", default="bench", help=argparse.SUPPRESS)
    parser.add_argument("--endpoint", help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.role == "publisher":
        return publisher_main(args.endpoint, args.fps, args.duration)
    results = previous_results()  # sections skipped this time keep their last figures
    if "compute" not in args.skip:
        results["compute"] = bench_compute(args.runs)
    if "latency" not in args.skip:
        key = f"latency_{args.latency_detector}"
        results[key] = bench_latency(args.duration, args.fps, args.latency_detector)
    if "crossing" not in args.skip:
        results["crossings"] = bench_crossings(args.crossing_seconds, 10.0)
    write_results("perception", results)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
