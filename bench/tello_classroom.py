"""A classroom's cost on the laptop: N Tello bridges with video on, or on demand with nobody
watching, as one bridge process per Tello or as one process for all N.

N Tello stand-ins live in this process, each on a loopback address of its own: they answer
``command``, ``streamon``/``streamoff`` and reads at once, send a state string at 10 Hz and,
while ``streamon`` is in force, 960x720 H.264 at 30 fps (the simulated Tello's own encoder,
libx264 ultrafast/zerolatency at 1.5 Mbit/s, a key frame every 30 frames, encoded once before
the run and replayed in a loop, so the stand-ins cost little next to the bridges). Each
arrangement is started afresh on one loopback Zenoh router (in this process) with nobody
subscribing to a camera; after the bridges are connected and settled, the bridges' CPU (user +
system, share of one core) is measured over ``--seconds``, with their memory (RSS) and the
reconnections the Tellos saw meanwhile (a ``command`` after the first: a bridge that missed
state strings for ``link_timeout``, 1.5 s):

* ``per Tello, video on``: N ``python -m dronewrapper_bridge_tello`` processes, ``video=on``
  (and ``video=off``, the floor);
* ``per Tello, on demand``: the same with ``video=on_demand`` (the classroom graph's default);
* ``one process, ...``: the N bridges in one process (``--host``: N nodes, N bridges, one
  interpreter), each mode.

After the ``per Tello, on demand`` window a viewer subscribes to drone1's camera: the time from
its subscription to ``streamon`` at the Tello and to the first decoded frame, and from its
leaving to ``streamoff`` (the bridge's ``video_idle_s``, 10 s), are printed too. The machine's
load average is recorded with each window (the figures are shares of a shared machine).

Run: ``.venv/bin/python -m bench.tello_classroom [--tellos 3] [--seconds 20]``; writes
bench/results/tello_classroom.json.
"""

from __future__ import annotations

import argparse
import os
import random
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import numpy as np

from bench.common import cpu_seconds, print_table, started_router, stop_process, write_results
from bench.tello_standin import TelloStandIn
from dronewrapper.runtime.arguments import CommandParser, first_line
from dronewrapper_sim.tello.video import H264Encoder, packetise

REPO = Path(__file__).resolve().parents[1]
W, H, FPS, LOOP_FRAMES = 960, 720, 30.0, 60
ARRANGEMENTS = (  # (label, one process for all, video mode)
    ("per Tello, video off", False, "off"),
    ("per Tello, video on", False, "on"),
    ("per Tello, on demand", False, "on_demand"),
    ("one process, video on", True, "on"),
    ("one process, on demand", True, "on_demand"),
)


def encoded_loop() -> list[list[bytes]]:
    """``LOOP_FRAMES`` frames of a moving gradient, H.264, each as its 1460-byte datagrams."""
    encoder = H264Encoder(W, H, FPS, 1500, 30)
    frames = []
    for i in range(LOOP_FRAMES):
        img = np.empty((H, W, 3), np.uint8)
        img[:] = ((np.arange(W) + 8 * i) % 256).astype(np.uint8)[None, :, None]
        img[:, :, 2] = (np.arange(H) // 3 % 256).astype(np.uint8)[:, None]
        frames.append(packetise(encoder.encode(img)))
    encoder.close()
    return frames


def rss_mb(pid: int) -> float:
    """Resident memory of ``pid``, MB."""
    for line in Path(f"/proc/{pid}/status").read_text().splitlines():
        if line.startswith("VmRSS:"):
            return int(line.split()[1]) / 1024
    return float("nan")


def bridge_args(endpoint: str, ns: str, address: str, video: str) -> list[str]:
    return [
        "--connect", endpoint, "--namespace", ns, "--tello", address, "--local", address,
        "--set", f"video={video}", "--set", "commander_lost_timeout=3600",
    ]  # fmt: skip


def host(endpoint: str, addresses: list[str], video: str) -> int:
    """One process for N Tellos: a node and a bridge per Tello, until SIGINT/SIGTERM."""
    from dronewrapper.runtime import Node, ZenohOptions
    from dronewrapper.runtime.config import load_config
    from dronewrapper_bridge_tello.config import Config
    from dronewrapper_bridge_tello.node import Bridge

    stop = threading.Event()
    for sig in (signal.SIGINT, signal.SIGTERM):
        signal.signal(sig, lambda *_: stop.set())
    running = []
    for i, address in enumerate(addresses, 1):
        options = ZenohOptions(connect=[endpoint], namespace=f"drone{i}", name="bridge_tello")
        node = Node("bridge_tello", options, handle_signals=False)
        overrides = [f"tello_address={address}", f"local_address={address}", f"video={video}"]
        config = load_config(Config, None, [*overrides, "commander_lost_timeout=3600"])
        bridge = Bridge(node, config)
        running.append((node, bridge, bridge.start()))
        node.announce()
    stop.wait()
    for node, _, _ in running:
        node.stop()
    for node, bridge, threads in running:
        for thread in threads:
            thread.join(2)
        bridge.camera.close()
        bridge.link.close()
        node.close()
    return 0


def measure(
    endpoint: str,
    tellos: list[TelloStandIn],
    one_process: bool,
    video: str,
    seconds: float,
    viewer: bool = False,
) -> dict[str, object]:
    """Start the bridges, wait until each Tello is switched, settle, measure (then, with
    ``viewer``, :func:`watch_once`), stop."""
    for tello in tellos:
        tello.reset()
    if one_process:
        addresses = ",".join(t.address for t in tellos)
        argv = [[sys.executable, "-m", "bench.tello_classroom", "--host", addresses,
                 "--endpoint", endpoint, "--video", video]]  # fmt: skip
    else:
        argv = [
            [sys.executable, "-m", "dronewrapper_bridge_tello", "--log-level", "WARNING",
             *bridge_args(endpoint, f"drone{i}", t.address, video)]
            for i, t in enumerate(tellos, 1)
        ]  # fmt: skip
    procs = [subprocess.Popen(a, cwd=REPO) for a in argv]
    try:
        wanted = {"on": "streamon", "on_demand": "streamoff"}.get(video)

        def ready(tello: TelloStandIn) -> bool:
            if wanted is None:  # off: connected is all there is to wait for
                return tello.commands > 0
            return wanted in [w for _, w in tello.switches]

        deadline = time.monotonic() + 60
        while not all(ready(t) for t in tellos):
            if time.monotonic() > deadline or any(p.poll() is not None for p in procs):
                raise RuntimeError(f"the bridges did not switch every Tello's video ({wanted})")
            time.sleep(0.2)
        time.sleep(3.0)  # settle: imports done, decoders warm
        sent0, commands0 = sum(t.datagrams for t in tellos), sum(t.commands for t in tellos)
        c0, w0 = sum(cpu_seconds(p.pid) for p in procs), time.monotonic()
        time.sleep(seconds)
        cpu = (sum(cpu_seconds(p.pid) for p in procs) - c0) / (time.monotonic() - w0)
        rss = sum(rss_mb(p.pid) for p in procs)
        datagrams = sum(t.datagrams for t in tellos) - sent0
        reconnections = sum(t.commands for t in tellos) - commands0
        n = len(tellos)
        out: dict[str, object] = {
            "cpu_share_one_core": round(cpu, 4),
            "cpu_share_per_tello": round(cpu / n, 4),
            "rss_mb": round(rss, 1),
            "rss_mb_per_tello": round(rss / n, 1),
            "video_datagrams_per_s": round(datagrams / seconds, 1),
            "reconnections": reconnections,
            "loadavg_1min_after": round(os.getloadavg()[0], 2),
        }
        if viewer:
            out["viewer"] = watch_once(endpoint, tellos[0])
    finally:
        for proc in procs:
            stop_process(proc, signal.SIGTERM)
    return out


def watch_once(endpoint: str, tello: TelloStandIn) -> dict[str, float]:
    """A viewer subscribes to drone1's camera until its first frame, then leaves: the times
    (s) to ``streamon``, to the first frame, and from leaving to ``streamoff``."""
    from dronewrapper.msgs import registry
    from dronewrapper.runtime import Node, ZenohOptions

    options = ZenohOptions(connect=[endpoint], namespace="drone1", name="viewer")
    first = threading.Event()
    with Node("viewer", options, handle_signals=False) as node:
        t0 = time.monotonic()
        node.subscribe(registry.IMAGE_RAW, lambda _msg: first.set(), camera="cam_frontal")
        if not first.wait(30):
            raise RuntimeError("no frame within 30 s of subscribing")
        t_frame = time.monotonic()
    gone = time.monotonic()
    deadline = gone + 60
    while not any(w == "streamoff" and at > gone for at, w in tello.switches):
        if time.monotonic() > deadline:
            raise RuntimeError("no streamoff within 60 s of the viewer leaving")
        time.sleep(0.05)
    t_on = next(at for at, w in tello.switches if w == "streamon" and at > t0)
    t_off = next(at for at, w in tello.switches if w == "streamoff" and at > gone)
    return {
        "subscribe_to_streamon_s": round(t_on - t0, 3),
        "subscribe_to_first_frame_s": round(t_frame - t0, 3),
        "leave_to_streamoff_s": round(t_off - gone, 3),
    }


def main(argv: list[str] | None = None) -> int:
    parser = CommandParser(description=first_line(__doc__))
    parser.add_argument("--tellos", type=int, default=3, help="how many Tellos (N)")
    parser.add_argument("--seconds", type=float, default=20.0, help="CPU measuring window, s")
    parser.add_argument("--host", help=argparse.SUPPRESS)  # one process: the Tellos' addresses
    parser.add_argument("--endpoint", help=argparse.SUPPRESS)
    parser.add_argument("--video", default="on_demand", help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.host:
        return host(args.endpoint, args.host.split(","), args.video)

    video = encoded_loop()
    net = f"127.{random.randint(10, 250)}.{random.randint(0, 255)}"

    def replay(index: int) -> list[bytes]:
        return video[index % LOOP_FRAMES]

    tellos = [TelloStandIn(f"{net}.{i}", replay) for i in range(1, args.tellos + 1)]
    router = started_router()
    results: dict[str, object] = {"tellos": args.tellos, "seconds": args.seconds}
    try:
        for label, one_process, mode in ARRANGEMENTS:
            viewer = label == "per Tello, on demand"
            results[label] = measure(
                router.endpoint, tellos, one_process, mode, args.seconds, viewer
            )
            print(f"{label}: {results[label]}", flush=True)
    finally:
        for tello in tellos:
            tello.close()
        router.stop(5)
    rows = [
        [label, f"{r['cpu_share_one_core']:.1%}", f"{r['cpu_share_per_tello']:.1%}",
         r["rss_mb"], r["video_datagrams_per_s"], r["reconnections"]]
        for label, r in ((label, results[label]) for label, _, _ in ARRANGEMENTS)
    ]  # fmt: skip
    print_table(
        f"{args.tellos} Tello bridges, nobody watching a camera ({args.seconds:g} s windows)",
        ["arrangement", "CPU (1 core)", "per Tello", "RSS MB", "video datagrams/s", "reconn."],
        rows,
    )
    on, demand = results["per Tello, video on"], results["per Tello, on demand"]
    saved = on["cpu_share_one_core"] - demand["cpu_share_one_core"]  # type: ignore[index]
    print(f"\non demand saves {saved:.1%} of a core for {args.tellos} Tellos nobody watches")
    seen = demand["viewer"]  # type: ignore[index]
    print(
        f"a viewer of drone1: streamon {seen['subscribe_to_streamon_s']:.2f} s and first frame "
        f"{seen['subscribe_to_first_frame_s']:.2f} s after subscribing; streamoff "
        f"{seen['leave_to_streamoff_s']:.1f} s after leaving"
    )
    write_results("tello_classroom", results)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
