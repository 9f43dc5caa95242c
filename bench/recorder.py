"""Recorder and replayer benchmark: recorder CPU and disk rate at full camera rate, raw and
JPEG-compressed; replay timing accuracy.

* Recorder: a loopback router and a publisher (this process) send the frontal camera at 30 Hz
  (640x480 bgr8, a real photo shifted each frame), the pose at 50 Hz and detections at 30 Hz;
  ``dronewrapper record`` (a child process) records them for ``--seconds``. Figures: the
  recorder's CPU (child rusage, % of one core), the file's growth (MB/s), messages dropped.
* Replay: a recording of 100 Hz poses is replayed by ``dronewrapper.record.replayer`` in this
  process while a subscriber in the same session measures each message's arrival against its
  due time (start + recorded offset), so the figure includes Zenoh delivery.

    python -m bench.recorder [--seconds 10]
"""

from __future__ import annotations

import resource
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

import cv2
import numpy as np

from bench.common import percentiles, print_table, started_router, write_results
from dronewrapper.msgs import Detections, Header, Image, PoseStamped, codec, registry
from dronewrapper.record.reader import read_bus, summarize
from dronewrapper.record.recorder import Recorder
from dronewrapper.record.replayer import replay
from dronewrapper.runtime import Node, ZenohOptions, open_session
from dronewrapper.runtime.arguments import CommandParser, first_line

REPO = Path(__file__).resolve().parents[1]
PHOTO = REPO / "assets" / "images" / "basketball1.png"


def _frames() -> list[bytes]:
    photo = cv2.resize(cv2.imread(str(PHOTO)), (640, 480))
    return [np.roll(photo, 4 * i, axis=1).tobytes() for i in range(30)]


def bench_recorder(endpoint: str, seconds: float, compressed: bool) -> dict[str, object]:
    frames = _frames()
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "bench.mcap"
        argv = [sys.executable, "-m", "dronewrapper", "record", "drone/**", "-o", str(out)]
        argv += ["--connect", endpoint, "--duration", str(seconds + 1.0)]
        argv += ["--compressed-images"] if compressed else []
        before = resource.getrusage(resource.RUSAGE_CHILDREN)
        child = subprocess.Popen(argv, stdout=subprocess.PIPE, text=True)
        options = ZenohOptions(mode="client", connect=[endpoint])
        sent = 0
        with Node("bench_pub", options, handle_signals=False) as node:
            cam = node.publisher(registry.IMAGE_RAW, camera="cam_frontal")
            pose = node.publisher(registry.LOCAL_POSE)
            dets = node.publisher(registry.DETECTIONS)
            time.sleep(1.0)  # the recorder subscribes
            t0 = time.monotonic()
            tick = 0
            while (now := time.monotonic()) - t0 < seconds:
                stamp = time.time()
                if tick % 5 == 0:  # 150 Hz base: camera/detections every 5th, pose every 3rd
                    img = Image(header=Header(stamp=stamp, frame_id="cam_frontal"), height=480,
                                width=640, step=1920, data=frames[(tick // 5) % 30])  # fmt: skip
                    cam.put(img)
                    dets.put(Detections(header=Header(stamp=stamp)))
                    sent += 2
                if tick % 3 == 0:
                    pose.put(PoseStamped(header=Header(stamp=stamp)))
                    sent += 1
                tick += 1
                time.sleep(max(0.0, t0 + tick / 150 - time.monotonic()))
            elapsed = now - t0
        output, _ = child.communicate(timeout=60)
        after = resource.getrusage(resource.RUSAGE_CHILDREN)
        cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
        info = summarize(out)
        frames_kept = sum(c.count for c in info.channels if c.topic.endswith("image_raw"))
    return {
        "images": "JPEG q80" if compressed else "raw bgr8",
        "cpu_percent_of_core": 100.0 * cpu / (seconds + 1.0),
        "disk_MB_per_s": info.size / 1e6 / elapsed,
        "frames_recorded": frames_kept,
        "frames_sent": int(elapsed * 30),
        "messages_sent": sent,
        "recorder_said": output.strip().splitlines()[-1] if output.strip() else "",
    }


def bench_replay(endpoint: str, seconds: float) -> dict[str, object]:
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "poses.mcap"
        t_start = 1.7e9
        with path.open("wb") as f, Recorder(f) as rec:
            for i in range(int(seconds * 100)):
                t = t_start + i / 100
                msg = PoseStamped(header=Header(stamp=t, seq=i))
                rec.write(registry.LOCAL_POSE.key(), codec.encode(msg), int(t * 1e9))
        offsets = {m.decode().header.seq: m.log_time_ns / 1e9 - t_start for m in read_bus(path)}
        session = open_session(ZenohOptions(mode="client", connect=[endpoint]))
        arrivals: dict[int, float] = {}

        def on_pose(sample) -> None:
            msg = codec.decode(PoseStamped, sample.payload.to_bytes())
            arrivals[msg.header.seq] = time.monotonic()

        sub = session.declare_subscriber(registry.LOCAL_POSE.key(), on_pose)
        time.sleep(0.5)
        stop = threading.Event()
        stats = replay(session, path, stop)
        time.sleep(0.5)
        sub.undeclare()
        session.close()
    first = min(arrivals)
    base = arrivals[first] - offsets[first]
    errors = [arrivals[s] - (base + offsets[s]) for s in sorted(arrivals)]
    return {
        "messages": len(offsets),
        "received": len(arrivals),
        "publish_late": percentiles(stats.lateness),
        "arrival_error": percentiles(np.abs(errors).tolist()),
    }


def main() -> int:
    parser = CommandParser(description=first_line(__doc__))
    parser.add_argument("--seconds", type=float, default=10.0)
    args = parser.parse_args()
    router = started_router()
    endpoint = router.endpoint
    try:
        rec = [bench_recorder(endpoint, args.seconds, c) for c in (False, True)]
        rep = bench_replay(endpoint, args.seconds)
    finally:
        router.stop(10)
    print_table(
        f"recorder at full camera rate ({args.seconds:g} s: 640x480 at 30 Hz + pose 50 Hz "
        "+ detections 30 Hz)",
        ["images", "CPU % of a core", "disk MB/s", "frames kept / sent"],
        [
            [r["images"], r["cpu_percent_of_core"], r["disk_MB_per_s"],
             f"{r['frames_recorded']} / {r['frames_sent']}"]
            for r in rec
        ],
    )  # fmt: skip
    print_table(
        "replay timing (100 Hz poses, arrival at a subscriber vs due time)",
        ["what", "p50 ms", "p90 ms", "p99 ms", "max ms"],
        [
            ["publish late", *(rep["publish_late"][k] for k in ("p50_ms", "p90_ms", "p99_ms",
                                                                   "max_ms"))],
            ["arrival error", *(rep["arrival_error"][k] for k in ("p50_ms", "p90_ms", "p99_ms",
                                                                    "max_ms"))],
        ],
    )  # fmt: skip
    print(f"replayed {rep['received']} / {rep['messages']} messages received")
    write_results("recorder", {"recorder": rec, "replay": rep})
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
