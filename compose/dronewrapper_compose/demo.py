"""``make demo``: the simulated Iris follows the red beacon, with live status and a summary.

Runs the ``sim_follow_color`` graph (simulator, MAVLink bridge, colour perception, controller)
through the launcher's Python API on a free loopback router and free UDP ports, watches the
simulator's ground truth and the controller's status, prints one live status line, and at the
end prints a summary (time to acquire, share of time the target was centred, distance error)
and saves a plot of the trajectories (top view) and the errors over time to ``out/demo/`` (and,
with ``--video``, perception's annotated frames with the status line as ``follow.mp4``; with
``--record``, the whole bus as ``flight.mcap`` to open in Foxglove, camera frames as JPEG).

    python -m dronewrapper_compose.demo [--duration 60] [--scenario beacon_smooth] [--out DIR]
                                        [--video] [--record]

The processes' own logs go to ``out/demo/graph.log``.
"""

from __future__ import annotations

import math
import sys
import threading
import time
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from dronewrapper.runtime.arguments import CommandParser, first_line
from dronewrapper.runtime.config import load_config
from dronewrapper.runtime.node import open_session
from dronewrapper.runtime.options import ZenohOptions
from dronewrapper_compose.graph import REPO
from dronewrapper_compose.launcher import Launcher, LaunchError
from dronewrapper_compose.ports import free_port, private_links
from dronewrapper_controller.config import Config as ControllerConfig
from dronewrapper_sim.evaluation.metrics import (
    FollowSample,
    FollowSummary,
    colour_intended_distance,
    summarize,
)
from dronewrapper_sim.evaluation.monitor import FollowMonitor

GRAPH = REPO / "compose" / "sim_follow_color.yaml"
CONTROLLER_CONFIG = (
    REPO / "services/controller/dronewrapper_controller" / "config" / "iris_sim.yaml"
)
CENTRED_TOLERANCE = math.radians(10.0)
DISTANCE_TOLERANCE = 1.5


def intended_distance(scenario_name: str) -> float:
    """Where the controller's config wants the drone: from the target radius and the camera."""
    from dronewrapper_sim.world.scenario import load_scenario

    scenario = load_scenario(scenario_name)
    target = next(o for o in scenario.objects if o.name == "target")
    cfg = load_config(ControllerConfig, CONTROLLER_CONFIG)
    cam = scenario.camera
    return colour_intended_distance(
        cfg.follow_color.target_radius,
        cfg.ref_width,
        cam.width,
        math.radians(cam.hfov_deg),
        target.radius_m,
    )


def status_line(t: float, sample: FollowSample | None, goal: float) -> str:
    """The live one-line status."""
    if sample is None:
        return f"t={t:5.1f}s  waiting for the simulator..."
    visible = "yes" if sample.target_visible else "no "
    return (
        f"t={t:5.1f}s  state={sample.state or '-':<8} target visible={visible}  "
        f"distance={sample.distance:5.2f} m (goal {goal:.1f})  "
        f"bearing={math.degrees(sample.bearing):+6.1f} deg  "
        f"elevation={math.degrees(sample.elevation):+6.1f} deg  alt={sample.vehicle[2]:4.1f} m"
    )


def print_summary(summary: FollowSummary, out=sys.stdout) -> None:
    """The end-of-run summary table."""
    rows = [
        ("servoing time", f"{summary.duration:.1f} s"),
        ("time to acquire", f"{summary.time_to_acquire:.1f} s"),
        (
            f"target centred (within {math.degrees(CENTRED_TOLERANCE):.0f} deg)",
            f"{100 * summary.centred_share:.0f} % of the time",
        ),
        ("target seen by the controller", f"{100 * summary.visible_share:.0f} % of the time"),
        ("intended distance", f"{summary.intended_distance:.2f} m"),
        (
            "distance error mean / p95",
            f"{summary.distance_mean:.2f} / {summary.distance_p95:.2f} m",
        ),
        (
            f"within {DISTANCE_TOLERANCE:g} m of the intended distance",
            f"{100 * summary.distance_share:.0f} % of the time",
        ),
        ("bearing error p95", f"{math.degrees(summary.bearing_p95):.1f} deg"),
    ]
    width = max(len(name) for name, _ in rows)
    print("\nsummary (from the simulator's ground truth, after take-off):", file=out)
    for name, value in rows:
        print(f"  {name:<{width}}  {value}", file=out)


def save_plot(samples: Sequence[FollowSample], goal: float, path: Path) -> None:
    """Top view of the trajectories and the errors over time (PNG, matplotlib Agg)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (top, err) = plt.subplots(1, 2, figsize=(13, 5.5))
    vx = [s.vehicle[0] for s in samples]
    vy = [s.vehicle[1] for s in samples]
    top.plot([s.target[0] for s in samples], [s.target[1] for s in samples], "r-", label="beacon")
    top.plot(vx, vy, "b-", label="drone")
    for s in samples[:: max(1, len(samples) // 25)]:  # heading arrows
        top.arrow(
            s.vehicle[0], s.vehicle[1], 0.6 * math.cos(s.yaw), 0.6 * math.sin(s.yaw),
            head_width=0.12, color="tab:blue", alpha=0.5,
        )  # fmt: skip
    top.plot(vx[:1], vy[:1], "bo", label="start")
    top.set(xlabel="east (m)", ylabel="north (m)", title="top view (ENU)", aspect="equal")
    top.legend(loc="best")
    top.grid(True, alpha=0.3)
    t = [s.t for s in samples]
    err.plot(t, [s.distance - goal for s in samples], label="distance - intended (m)")
    err.plot(t, [math.degrees(s.bearing) / 10 for s in samples], label="bearing error (10 deg)")
    err.plot(t, [math.degrees(s.elevation) / 10 for s in samples], label="elevation error (10 deg)")
    seen = [0.0 if s.target_visible else math.nan for s in samples]
    err.plot(t, seen, "g|", label="target seen")
    err.axhline(0.0, color="k", lw=0.5)
    err.set(xlabel="time (s)", title="errors over time")
    err.legend(loc="best")
    err.grid(True, alpha=0.3)
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    plt.close(fig)


class VideoRecorder:
    """Writes perception's annotated frames, with the live status drawn on, to an MP4 file."""

    def __init__(self, session, ns: str, path: Path, status_text, fps: float = 15.0) -> None:
        import cv2

        from dronewrapper.msgs import codec, registry
        from dronewrapper.msgs.sensor import CompressedImage

        self._cv2 = cv2
        self.path = path
        self.frames = 0
        self._status_text = status_text
        self._writer: cv2.VideoWriter | None = None
        self._fps = fps
        self._last = 0.0
        self._lock = threading.Lock()
        decoder = codec.decoder(CompressedImage)

        def on_frame(sample) -> None:
            now = time.monotonic()
            if now - self._last < 1.0 / self._fps:
                return
            self._last = now
            msg = decoder.decode(sample.payload.to_bytes())
            img = cv2.imdecode(np.frombuffer(msg.data, np.uint8), cv2.IMREAD_COLOR)
            if img is not None:
                self._write(img)

        self._sub = session.declare_subscriber(registry.DETECTIONS_DEBUG_IMAGE.key(ns), on_frame)

    def _write(self, img) -> None:
        cv2 = self._cv2
        text = self._status_text()
        cv2.rectangle(img, (0, img.shape[0] - 24), (img.shape[1], img.shape[0]), (0, 0, 0), -1)
        cv2.putText(
            img, text, (6, img.shape[0] - 8), cv2.FONT_HERSHEY_SIMPLEX, 0.42, (255, 255, 255), 1
        )
        with self._lock:
            if self._writer is None:
                size = (img.shape[1], img.shape[0])
                fourcc = cv2.VideoWriter_fourcc(*"mp4v")
                self._writer = cv2.VideoWriter(str(self.path), fourcc, self._fps, size)
            self._writer.write(img)
            self.frames += 1

    def close(self) -> None:
        self._sub.undeclare()
        with self._lock:
            if self._writer is not None:
                self._writer.release()


RECORDED_KEYS = (
    "drone/mavros/**",
    "drone/perception/**",
    "drone/controller/**",
    "drone/sim/**",
    "drone/cam_frontal/image_raw",  # JPEG-compressed by the recorder; the sim's own JPEG
    "sim/**",  # stream and the ventral camera would only double the file
)


def run_demo(
    duration: float,
    scenario: str,
    out_dir: Path,
    *,
    live: bool = True,
    video: bool = False,
    record: bool = False,
) -> tuple[int, FollowSummary | None]:
    """Fly the demo; returns (exit status, summary)."""
    out_dir.mkdir(parents=True, exist_ok=True)
    router = f"tcp/127.0.0.1:{free_port()}"
    variables = {
        "scenario": scenario,
        **private_links(),
        "on_exit": "land",
        "debug_image": "true" if video else "false",
    }
    goal = intended_distance(scenario)
    log_path = out_dir / "graph.log"
    print(f"starting sim_follow_color ({scenario}); process logs in {log_path}")
    with open(log_path, "w") as log_file:
        launcher = Launcher.from_file(GRAPH, router=router, variables=variables, out=log_file)
        try:
            launcher.start()
        except LaunchError as exc:
            launcher.stop()
            print(f"demo: the graph did not start: {exc} (see {log_path})", file=sys.stderr)
            return 1, None
        session = open_session(ZenohOptions(mode="client", connect=[router]))
        monitor = FollowMonitor(session, launcher.ns, aim_height=0.0).start()
        t0 = time.monotonic()
        recorder = None
        if video:

            def short() -> str:
                smp = monitor.sample()
                if smp is None:
                    return ""
                return (
                    f"t={time.monotonic() - t0:5.1f}s {smp.state:<8} "
                    f"seen={'yes' if smp.target_visible else 'no'} d={smp.distance:4.1f} m "
                    f"(goal {goal:.1f}) bearing={math.degrees(smp.bearing):+5.1f} deg "
                    f"alt={smp.vehicle[2]:3.1f} m"
                )

            recorder = VideoRecorder(session, launcher.ns, out_dir / "follow.mp4", short)
        recording = None
        if record:
            from dronewrapper.record.capture import BackgroundRecording

            recording = BackgroundRecording(session, RECORDED_KEYS, out_dir / "flight.mcap")
        print(f"flying for {duration:g} s (Ctrl-C stops early)")
        tty = sys.stdout.isatty()
        last_print = 0.0
        try:
            while time.monotonic() - t0 < duration:
                dead = [c.name for c in launcher.children if c.poll() is not None]
                if dead:
                    print(f"\ndemo: {', '.join(dead)} stopped unexpectedly", file=sys.stderr)
                    break
                time.sleep(0.25)
                now = time.monotonic() - t0
                if live and (tty or now - last_print >= 5.0):
                    line = status_line(now, monitor.sample(), goal)
                    print(f"\r{line}\033[K" if tty else line, end="" if tty else "\n", flush=True)
                    last_print = now
        except KeyboardInterrupt:
            print("\ninterrupted")
        finally:
            if tty:
                print()
            monitor.close()
            if recorder is not None:
                recorder.close()
                print(f"video: {recorder.frames} frames saved to {recorder.path}")
            if recording is not None:
                recording.close()
                print(
                    f"recording: {recording.stats.written} messages saved to {recording.path} "
                    "(open it in Foxglove with docs/foxglove_layout.json)"
                )
            session.close()
            print("stopping the graph (the drone lands first)...")
            code = launcher.stop()
        samples = list(monitor.samples)
    summary = summarize(
        samples,
        intended_distance=goal,
        centred_tolerance=CENTRED_TOLERANCE,
        distance_tolerance=DISTANCE_TOLERANCE,
    )
    print_summary(summary)
    if samples:
        plot = out_dir / "follow.png"
        save_plot(samples, goal, plot)
        print(f"\nplot saved to {plot}")
    if code != 0:
        print(f"demo: the graph reported failures: {launcher.failures}", file=sys.stderr)
    return code, summary


def main(argv: Sequence[str] | None = None) -> int:
    parser = CommandParser(prog="make demo", description=first_line(__doc__))
    parser.add_argument("--duration", type=float, default=60.0, help="seconds of flight")
    parser.add_argument("--scenario", default="beacon_smooth", help="a beacon_* scenario")
    parser.add_argument("--out", type=Path, default=REPO / "out" / "demo", help="output folder")
    parser.add_argument(
        "--video", action="store_true", help="also save an annotated video (follow.mp4)"
    )
    parser.add_argument(
        "--record", action="store_true", help="also record the bus to flight.mcap (Foxglove)"
    )
    args = parser.parse_args(argv)
    if not args.duration > 0:
        parser.error("--duration must be > 0")
    code, _ = run_demo(args.duration, args.scenario, args.out, video=args.video, record=args.record)
    return code


if __name__ == "__main__":
    raise SystemExit(main())
