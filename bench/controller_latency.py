"""Glass-to-setpoint latency of the follow graphs, against the pipeline's own compute time.

1. In one process (no middleware): render a frame of the scenario, run the perception
   pipeline (detector + tracker), build the Detections message, encode/decode it, and run the
   controller's servo step: the compute a frame needs, p50/p99 (the render time is shown apart).
2. Through the real graph (``sim_follow_color`` on beacon_static, ``sim_follow_person`` on
   person_static with YOLOX): every process separate, on a loopback router. For each camera frame
   that produced a command, latency = arrival time of the first setpoint carrying the frame's
   stamp at a subscriber standing in for the bridge - the frame's capture stamp. Also the
   frame-to-detections latency.

The difference between (2) and (1) is what the processes and Zenoh add.
Run: ``python -m bench.controller_latency [--seconds 30]``; writes results/controller_latency.json.
"""

from __future__ import annotations

import math
import sys
import threading
import time
from pathlib import Path

import numpy as np

from bench.common import percentiles, print_table, probed_graph, write_results
from dronewrapper.msgs import codec, registry
from dronewrapper.msgs.mavros import MASK_VELOCITY, PositionTarget
from dronewrapper.msgs.vision import Detections
from dronewrapper.runtime.arguments import CommandParser, first_line
from dronewrapper.runtime.config import load_config
from dronewrapper_compose.ports import free_port, private_links

REPO = Path(__file__).resolve().parents[1]
ASSETS = REPO / "assets"

CASES = [
    # name, graph, scenario, detector
    ("colour", "sim_follow_color", "beacon_static", "color"),
    ("yolox", "sim_follow_person", "person_static", "yolox"),
]


def in_process(scenario_name: str, detector: str, frames: int) -> dict[str, object]:
    """Per-frame compute of render, perception and control in one process (seconds)."""
    from dronewrapper_controller.config import Config as ControllerConfig
    from dronewrapper_controller.servo import Servo
    from dronewrapper_perception.config import Config as PerceptionConfig
    from dronewrapper_perception.pipeline import Pipeline, to_message
    from dronewrapper_sim.render.camera import FRONTAL, PinholeCamera
    from dronewrapper_sim.render.renderer import Renderer
    from dronewrapper_sim.world.scenario import load_scenario
    from dronewrapper_sim.world.world import World

    scenario = load_scenario(scenario_name)
    world = World(scenario)
    cam = scenario.camera
    camera = PinholeCamera(cam.width, cam.height, math.radians(cam.hfov_deg))
    renderer = Renderer(world, camera, ASSETS / "sprites")
    overrides = [f"detector={detector}"]
    if detector == "yolox":
        overrides.append(f"model_path={ASSETS / 'models' / 'yolox_nano.onnx'}")
    pipeline = Pipeline(load_config(PerceptionConfig, None, overrides))
    pipeline.warm_up(cam.width, cam.height)
    mode = "follow_color" if detector == "color" else "follow_person"
    servo = Servo(
        load_config(
            ControllerConfig,
            REPO / "services/controller/dronewrapper_controller/config/iris_sim.yaml",
            [f"mode={mode}"],
        )
    )
    decoder = codec.decoder(Detections)
    quat = np.array([0.0, 0.0, 0.0, 1.0])
    height = 2.5 if detector == "color" else 1.0
    render_s, compute_s = [], []
    for k in range(frames):
        world.step(1.0 / cam.rate_hz)
        t0 = time.perf_counter()
        bgr = renderer.render(FRONTAL, np.array([0.0, 0.0, height]), quat)
        t1 = time.perf_counter()
        stamp = time.time()
        result = pipeline.process(bgr, k / cam.rate_hz)
        msg = decoder.decode(
            codec.encode(to_message(result, stamp=stamp, frame_id="cam_frontal", detector=detector))
        )
        servo.step(time.monotonic(), msg, 0.0)
        t2 = time.perf_counter()
        render_s.append(t1 - t0)
        compute_s.append(t2 - t1)
    return {"render": percentiles(render_s), "compute": percentiles(compute_s)}


class Probe:
    """Stands in for the bridge: first arrival of each setpoint stamp, and detections."""

    def __init__(self, session, ns: str) -> None:
        self.setpoint_latency: list[float] = []
        self.detection_latency: list[float] = []
        self.processing: list[float] = []
        self.controller_hop: list[float] = []  # detections arrival -> setpoint arrival
        self._frame_stamps: dict[float, float] = {}  # frame stamp -> detections arrival
        self._seen: set[float] = set()
        self._lock = threading.Lock()
        sp_dec, det_dec = codec.decoder(PositionTarget), codec.decoder(Detections)

        def on_setpoint(sample) -> None:
            now = time.time()
            sp = sp_dec.decode(sample.payload.to_bytes())
            stamp = sp.header.stamp
            with self._lock:
                if sp.type_mask != MASK_VELOCITY or stamp in self._seen:
                    return
                if stamp in self._frame_stamps:
                    self._seen.add(stamp)
                    self.setpoint_latency.append(now - stamp)
                    self.controller_hop.append(now - self._frame_stamps[stamp])

        def on_detections(sample) -> None:
            now = time.time()
            det = det_dec.decode(sample.payload.to_bytes())
            with self._lock:
                self._frame_stamps[det.header.stamp] = now
                self.detection_latency.append(now - det.header.stamp)
                self.processing.append(det.processing_time)

        self._subs = [
            session.declare_subscriber(registry.SETPOINT_RAW_LOCAL.key(ns), on_setpoint),
            session.declare_subscriber(registry.DETECTIONS.key(ns), on_detections),
        ]

    def close(self) -> None:
        for sub in self._subs:
            sub.undeclare()


def through_graph(graph: str, scenario: str, detector: str, seconds: float) -> dict[str, object]:
    """Run the graph and measure latencies at a subscriber (seconds in, ms out)."""
    from dronewrapper_compose.launcher import Launcher

    router = f"tcp/127.0.0.1:{free_port()}"
    variables = {
        "scenario": scenario,
        **private_links(),
        "on_exit": "stop",
    }
    if graph == "sim_follow_person":
        variables["detector"] = detector
    log_path = REPO / "out" / "bench" / f"controller_latency_{graph}.log"
    log_path.parent.mkdir(parents=True, exist_ok=True)
    with open(log_path, "w") as log_file:
        launcher = Launcher.from_file(
            REPO / "compose" / f"{graph}.yaml", router=router, variables=variables, out=log_file
        )
        with probed_graph(launcher, router, Probe) as probe:
            time.sleep(seconds)
    return {
        "frame_to_setpoint": percentiles(probe.setpoint_latency),
        "frame_to_detections": percentiles(probe.detection_latency),
        "perception_processing": percentiles(probe.processing),
        "detections_to_setpoint": percentiles(probe.controller_hop),
    }


def main(argv: list[str] | None = None) -> int:
    parser = CommandParser(description=first_line(__doc__))
    parser.add_argument("--seconds", type=float, default=30.0, help="graph run per case")
    parser.add_argument("--frames", type=int, default=150, help="in-process frames per case")
    args = parser.parse_args(argv)
    results: dict[str, object] = {}
    rows = []
    for name, graph, scenario, detector in CASES:
        local = in_process(scenario, detector, args.frames)
        remote = through_graph(graph, scenario, detector, args.seconds)
        results[name] = {"graph": graph, "scenario": scenario, "in_process": local, **remote}
        e2e, comp, rend = remote["frame_to_setpoint"], local["compute"], local["render"]
        det, hop = remote["frame_to_detections"], remote["detections_to_setpoint"]
        overhead = e2e.get("p50_ms", math.nan) - comp["p50_ms"] - rend["p50_ms"]
        results[name]["middleware_overhead_p50_ms"] = overhead
        rows.append(
            [
                name,
                e2e.get("n", 0),
                e2e.get("p50_ms", math.nan),
                e2e.get("p99_ms", math.nan),
                det.get("p50_ms", math.nan),
                hop.get("p50_ms", math.nan),
                hop.get("p99_ms", math.nan),
                rend["p50_ms"],
                comp["p50_ms"],
                comp["p99_ms"],
                overhead,
            ]
        )
    print_table(
        "glass-to-setpoint latency (ms): graph of processes vs one process",
        [
            "detector",
            "frames",
            "frame->setpoint p50",
            "p99",
            "frame->detections p50",
            "det->setpoint p50",
            "p99",
            "render p50",
            "compute p50",
            "compute p99",
            "added p50",
        ],
        rows,
    )
    print(
        "\n'det->setpoint' = the controller process and its two Zenoh hops (detections in, setpoint"
        " out).\n'added' = graph p50 - (render p50 + compute p50): what separate processes and"
        " Zenoh add in all (raw 640x480 frames included, and waiting for a busy CPU on this"
        " shared 2-core machine)."
    )
    write_results("controller_latency", {"seconds": args.seconds, "cases": results})
    return 0


if __name__ == "__main__":
    sys.exit(main())
