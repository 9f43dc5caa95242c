"""Simulator camera rendering speed: frames/s and ms/frame at 640x480, both cameras.

For the beacon scene (beacon_abrupt, a moving beacon) and the crowd scene
(people_crossing_front, three procedural people; also with photo sprites), the world steps at
30 Hz while the vehicle flies a gentle climbing circle (so the ground, horizon and objects move
in the frame), and each step renders the frontal and the ventral camera. A last scene has the
vehicle standing still (person_static: the idle sim on the ground before take-off).
Measured per frame: wall time (perf_counter) and CPU time of this process (process_time, all
threads). The implied CPU share is the CPU of one frontal + one ventral frame times 30 Hz
(100 % = one core; target < 50 %). OpenCV runs single-threaded here (``cv2.setNumThreads(1)``)
so the figure is the cost, not a share of a multi-core speed-up.
Run: ``.venv/bin/python -m bench.sim_render [--frames 150]``; writes bench/results/sim_render.json.
"""

from __future__ import annotations

import math
import time
from pathlib import Path

import cv2
import numpy as np

from bench.common import percentiles, print_table, write_results
from dronewrapper.runtime.arguments import CommandParser, first_line
from dronewrapper_sim.render.camera import FRONTAL, VENTRAL, PinholeCamera
from dronewrapper_sim.render.renderer import Renderer
from dronewrapper_sim.world.scenario import load_scenario
from dronewrapper_sim.world.world import World

REPO = Path(__file__).resolve().parents[1]
SPRITES = REPO / "assets" / "sprites"
RATE_HZ = 30.0


def vehicle_pose(t: float) -> tuple[np.ndarray, np.ndarray]:
    """A slow climbing circle around the origin, nose along the path, 5 deg forward tilt."""
    angle = 0.15 * t
    pos = np.array([2.0 * math.sin(angle), 2.0 - 2.0 * math.cos(angle), 1.0 + 0.05 * t])
    yaw = angle - 0.3
    pitch = math.radians(5.0)
    cy, sy, cp, sp = math.cos(yaw / 2), math.sin(yaw / 2), math.cos(pitch / 2), math.sin(pitch / 2)
    quat = np.array([-sy * sp, cy * sp, sy * cp, cy * cp])  # yaw then pitch, x y z w
    return pos, quat


def run_scene(
    name: str, frames: int, sprites: Path | None, still: bool = False
) -> dict[str, object]:
    world = World(load_scenario(name))
    camera = PinholeCamera(640, 480, math.radians(world.scenario.camera.hfov_deg))
    t0 = time.perf_counter()
    renderer = Renderer(world, camera, sprites)
    setup_s = time.perf_counter() - t0
    for mount in (FRONTAL, VENTRAL):  # warm-up (texture, sprite cut-outs)
        renderer.render(mount, *vehicle_pose(0.0))
    walls: dict[str, list[float]] = {"cam_frontal": [], "cam_ventral": []}
    cpus: dict[str, list[float]] = {"cam_frontal": [], "cam_ventral": []}
    for i in range(frames):
        world.step(1.0 / RATE_HZ)
        pos, quat = vehicle_pose(0.0 if still else i / RATE_HZ)
        for mount in (FRONTAL, VENTRAL):
            c0, w0 = time.process_time(), time.perf_counter()
            image = renderer.render(mount, pos, quat)
            walls[mount.name].append(time.perf_counter() - w0)
            cpus[mount.name].append(time.process_time() - c0)
            assert image.shape == (480, 640, 3)
    out: dict[str, object] = {
        "scenario": name,
        "sprites": sprites is not None,
        "vehicle_still": still,
        "setup_s": setup_s,
    }
    both_cpu_ms = 0.0
    for cam in walls:
        wall = percentiles(walls[cam])
        cpu_ms = 1e3 * float(np.mean(cpus[cam]))
        both_cpu_ms += cpu_ms
        out[cam] = {**wall, "cpu_ms_mean": cpu_ms, "fps_wall": 1e3 / wall["p50_ms"]}
    out["both_cameras_cpu_share_at_30hz_percent"] = both_cpu_ms * RATE_HZ / 10.0
    return out


def main() -> None:
    parser = CommandParser(description=first_line(__doc__))
    parser.add_argument("--frames", type=int, default=150, help="frames per scene and camera")
    args = parser.parse_args()
    cv2.setNumThreads(1)
    scenes = [
        ("beacon_abrupt", None, False),
        ("people_crossing_front", None, False),
        ("people_crossing_front", SPRITES if SPRITES.is_dir() else None, False),
        ("person_static", None, True),
    ]
    results = [run_scene(name, args.frames, sprites, still) for name, sprites, still in scenes]
    rows = []
    for r in results:
        label = f"{r['scenario']}{' (sprites)' if r['sprites'] else ''}"
        label += " (vehicle still)" if r["vehicle_still"] else ""
        for cam in ("cam_frontal", "cam_ventral"):
            s = r[cam]
            rows.append(
                (
                    label,
                    cam,
                    s["p50_ms"],
                    s["p90_ms"],
                    s["cpu_ms_mean"],
                    s["fps_wall"],
                )
            )
        rows.append(
            (
                label,
                "both @30 Hz",
                "",
                "",
                "",
                f"{r['both_cameras_cpu_share_at_30hz_percent']:.0f} % CPU",
            )
        )
    print_table(
        f"sim render, 640x480, {args.frames} frames per camera, OpenCV 1 thread",
        ("scene", "camera", "wall p50 ms", "wall p90 ms", "cpu ms/frame", "frames/s"),
        rows,
    )
    write_results(
        "sim_render", {"frames": args.frames, "width": 640, "height": 480, "scenes": results}
    )


if __name__ == "__main__":
    main()
