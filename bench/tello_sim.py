"""The simulated Tello's cost: process CPU with the video on, and encode-to-UDP latency.

1. Process CPU: ``python -m dronewrapper_sim --aircraft tello`` on a loopback address with a
   Zenoh router (ground truth published), measured from ``/proc/PID/stat`` (utime + stime, all
   threads: flight, world, renderer, libx264's threads) over ``--seconds``: in SDK mode on the
   ground without video; streaming 960x720 30 fps on the ground; streaming while flying and
   turning (rc yaw, so that every frame changes); with the default ``render_scale`` 0.5 and
   with 1 (full-size rendering). 100 % = one core. Target: sim +
   encoder <= 35 % of one core at 960x720 30 fps. The client counts the frames it receives.
2. Encode-to-UDP latency per frame, in this process: the forward camera rendered while
   turning (rendered at the default ``render_scale`` and scaled up to 960x720 as the sim
   does), encoded by the sim's :class:`H264Encoder` and sent in 1460-byte datagrams to a
   loopback socket; from the start of the encode to the last datagram of the frame read back
   by the receiver (and the render time apart).
Run: ``python -m bench.tello_sim [--seconds 10]``; writes bench/results/tello_sim.json.
"""

from __future__ import annotations

import contextlib
import math
import socket
import subprocess
import sys
import threading
import time
from pathlib import Path

from bench.common import LoopbackRouter, percentiles, print_table, write_results
from bench.sim_physics import cpu_percent
from dronewrapper.runtime.arguments import CommandParser, first_line

REPO = Path(__file__).resolve().parents[1]


class Client:
    """A Tello SDK client on its own loopback address that counts video datagrams."""

    def __init__(self, drone: str, host: str) -> None:
        self.drone = (drone, 8889)
        self.cmd = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self.cmd.bind((host, 0))
        self.cmd.settimeout(0.5)
        self.video = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self.video.bind((host, 11111))
        self.video.settimeout(0.2)
        self.state = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self.state.bind((host, 8890))
        self.bytes = 0
        self.frames = 0  # datagrams shorter than the full size end a frame
        self.stop = threading.Event()
        threading.Thread(target=self._video, daemon=True).start()

    def _video(self) -> None:
        while not self.stop.is_set():
            with contextlib.suppress(OSError):
                data = self.video.recv(65535)
                self.bytes += len(data)
                if len(data) < 1460:
                    self.frames += 1

    def ask(self, text: str, timeout: float = 20.0) -> str:
        self.cmd.settimeout(timeout)
        self.cmd.sendto(text.encode(), self.drone)
        return self.cmd.recv(2048).decode()

    def send(self, text: str) -> None:
        self.cmd.sendto(text.encode(), self.drone)

    def close(self) -> None:
        self.stop.set()
        for sock in (self.cmd, self.video, self.state):
            sock.close()


def _window(pid: int, client: Client, seconds: float) -> dict[str, float]:
    frames0, bytes0, t0 = client.frames, client.bytes, time.monotonic()
    cpu = cpu_percent(pid, seconds)
    dt = time.monotonic() - t0
    return {
        "cpu_percent": cpu,
        "frames_per_s": (client.frames - frames0) / dt,
        "kbit_per_s": (client.bytes - bytes0) * 8 / 1000 / dt,
    }


def process_cpu(seconds: float, render_scale: float) -> dict[str, dict[str, float]]:
    zenoh_router = LoopbackRouter()
    zenoh_router.start()
    router = zenoh_router.endpoint
    drone, host = "127.77.0.10", "127.77.0.11"
    client = Client(drone, host)
    argv = [sys.executable, "-m", "dronewrapper_sim", "--aircraft", "tello", "--address", drone,
            "--connect", router, "--set", f"tello.render_scale={render_scale}"]  # fmt: skip
    proc = subprocess.Popen(argv, cwd=REPO, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    out: dict[str, dict[str, float]] = {}
    try:
        deadline = time.monotonic() + 30
        while True:
            try:
                if client.ask("command", timeout=0.5) == "ok":
                    break
            except OSError:
                if time.monotonic() > deadline:
                    raise RuntimeError("the simulated Tello did not answer within 30 s") from None
        time.sleep(2.0)
        out["sdk_mode_no_video"] = _window(proc.pid, client, seconds)
        client.ask("streamon")
        time.sleep(2.0)
        out["streaming_on_ground"] = _window(proc.pid, client, seconds)
        client.ask("takeoff")
        client.send("rc 0 0 0 40")  # turning: every frame changes
        keep = threading.Event()

        def keepalive() -> None:
            while not keep.wait(1.0):
                client.send("rc 0 0 0 40")

        threading.Thread(target=keepalive, daemon=True).start()
        time.sleep(1.0)
        out["streaming_flying_turning"] = _window(proc.pid, client, seconds)
        keep.set()
    finally:
        client.close()
        proc.send_signal(2)
        proc.wait(15)
        zenoh_router.stop()
    return out


def encode_latency(frames: int = 300) -> dict[str, dict[str, float]]:
    import cv2
    import numpy as np

    from dronewrapper.rotations import quat_from_rpy
    from dronewrapper_sim.render.camera import FRONTAL, PinholeCamera
    from dronewrapper_sim.render.renderer import Renderer
    from dronewrapper_sim.tello.config import TelloConfig
    from dronewrapper_sim.tello.params import camera_hfov_rad
    from dronewrapper_sim.tello.video import H264Encoder, packetise
    from dronewrapper_sim.world.scenario import load_scenario
    from dronewrapper_sim.world.world import World

    scale = TelloConfig().render_scale
    world = World(load_scenario("people_crossing_front"), seed=0)
    camera = PinholeCamera(round(960 * scale), round(720 * scale), camera_hfov_rad())
    renderer = Renderer(world, camera)
    encoder = H264Encoder(960, 720, 30.0, 1500, 30)
    rx = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    rx.bind(("127.0.0.1", 0))
    rx.settimeout(1.0)
    tx = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    render_s, encode_s, to_udp_s = [], [], []
    for i in range(frames):
        world.step(1 / 30)
        yaw = 0.6 * math.sin(i / 30)
        t0 = time.perf_counter()
        image = renderer.render(
            FRONTAL, np.array([0.0, 0.0, 1.0]), np.array(quat_from_rpy(0.0, 0.0, yaw))
        )
        image = cv2.resize(image, (960, 720), interpolation=cv2.INTER_LINEAR)
        t1 = time.perf_counter()
        unit = encoder.encode(image)
        t2 = time.perf_counter()
        datagrams = packetise(unit, 1460)
        for d in datagrams:
            tx.sendto(d, rx.getsockname())
        for _ in datagrams:
            rx.recv(65535)
        t3 = time.perf_counter()
        render_s.append(t1 - t0)
        encode_s.append(t2 - t1)
        to_udp_s.append(t3 - t1)
    rx.close()
    tx.close()
    return {
        "render": percentiles(render_s),
        "encode": percentiles(encode_s),
        "encode_to_udp_received": percentiles(to_udp_s),
    }


def main(argv: list[str] | None = None) -> int:
    parser = CommandParser(description=first_line(__doc__))
    parser.add_argument("--seconds", type=float, default=10.0, help="each CPU window, s")
    args = parser.parse_args(argv)
    cpu = {}
    for scale in (0.5, 1.0):
        name = f"render_scale {scale:g}"
        cpu[name] = process_cpu(args.seconds, scale)
        print_table(
            f"simulated Tello process CPU (% of one core, {args.seconds:g} s windows; "
            f"target <= 35), {name}",
            ["configuration", "CPU %", "frames/s received", "kbit/s"],
            [
                [k, v["cpu_percent"], v["frames_per_s"], v["kbit_per_s"]]
                for k, v in cpu[name].items()
            ],
        )
    latency = encode_latency()
    print_table(
        "per frame, 960x720 (ms; render = render at render_scale + scale up)",
        ["stage", "p50", "p90", "p99", "max"],
        [[name, v["p50_ms"], v["p90_ms"], v["p99_ms"], v["max_ms"]] for name, v in latency.items()],
    )
    write_results("tello_sim", {"process": cpu, "latency": latency, "seconds": args.seconds})
    return 0


if __name__ == "__main__":
    raise SystemExit(main(sys.argv[1:]))
