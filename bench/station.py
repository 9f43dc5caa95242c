"""Ground station: video latency in a real browser, and the station's CPU with two drones.

Starts a router, two simulated Iris graphs (``drone1``, ``drone2``) and ``dronewrapper
station``, then measures over ``--seconds`` each:

1. the station's CPU with no page open (telemetry of two drones, discovery);
2. with the page open in headless Chromium (Debian's chromium + chromium-driver), watching
   drone1's frontal camera: the station's CPU, the frames drawn per second, and the video
   latency = the page's clock when a frame is drawn minus the frame's capture stamp (same
   machine, same clock; includes JPEG encoding in the sim, the bus, the station, the
   WebSocket, decoding and drawing).

CPU is ``/proc/PID/stat`` utime + stime; 100 % = one core.
Run: ``python -m bench.station [--seconds 15]``; writes bench/results/station.json.
"""

from __future__ import annotations

import os
import socket
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from bench.common import percentiles, print_table, write_results
from bench.graph_cpu import cpu_seconds, free_port
from dronewrapper.runtime.arguments import CommandParser, first_line

REPO = Path(__file__).resolve().parents[1]
DRONES = ("drone1", "drone2")


def _spawn(argv: list[str], log: Path) -> subprocess.Popen:
    from dronewrapper.runtime.children import die_with_parent

    out = open(log, "wb")  # noqa: SIM115 - lives as long as the process
    return subprocess.Popen(
        argv, stdout=out, stderr=subprocess.STDOUT, cwd=REPO, preexec_fn=die_with_parent
    )


def _wait(predicate, timeout: float, what: str):
    deadline = time.monotonic() + timeout
    while not (value := predicate()):
        if time.monotonic() > deadline:
            raise RuntimeError(f"timed out waiting for {what}")
        time.sleep(0.2)
    return value


def _cpu_percent(pid: int, seconds: float, during=None) -> float:
    start, t0 = cpu_seconds(pid), time.monotonic()
    deadline = t0 + seconds
    while time.monotonic() < deadline:
        if during:
            during()
        time.sleep(0.5)
    return 100 * (cpu_seconds(pid) - start) / (time.monotonic() - t0)


def main(argv: list[str] | None = None) -> int:
    parser = CommandParser(description=first_line(__doc__))
    parser.add_argument("--seconds", type=float, default=15.0, help="each measuring window (s)")
    args = parser.parse_args(argv)
    from dronewrapper import list_drones
    from dronewrapper_ground_station.browser import chromium, console_errors

    logs = REPO / "out" / "bench"
    logs.mkdir(parents=True, exist_ok=True)
    router = f"tcp/127.0.0.1:{free_port()}"
    py = [sys.executable, "-m", "dronewrapper"]
    procs = [_spawn([*py, "router", "--listen", router], logs / "station_router.log")]
    try:
        for ns in DRONES:
            udp = [free_port(socket.SOCK_DGRAM) for _ in range(2)]
            graph = [*py, "up", "compose/sim_iris.yaml", "--router", router, "--use-router"]
            graph += ["--ns", ns, "--var", f"onboard_port={udp[0]}", "--var", f"gcs_port={udp[1]}"]
            procs.append(_spawn(graph, logs / f"station_{ns}.log"))
        _wait(lambda: set(DRONES) <= set(list_drones(router, timeout=1.0)), 90, "two bridges")
        port = free_port()
        station_log = logs / "station_station.log"
        station = _spawn([*py, "station", "--connect", router, "--port", str(port)], station_log)
        procs.append(station)
        _wait(lambda: "station: open" in station_log.read_text(), 30, "the station")
        time.sleep(3.0)  # discovery, subscriptions settle
        idle = _cpu_percent(station.pid, args.seconds)

        ages: list[float] = []
        with tempfile.TemporaryDirectory() as profile, chromium(Path(profile)) as driver:
            driver.get(f"http://127.0.0.1:{port}/")
            _wait(lambda: driver.execute_script("return window.station.ns"), 30, "a drone")
            driver.find_element("id", "drone-drone1").click()
            _wait(lambda: driver.execute_script("return window.station.frames") > 10, 30, "video")
            driver.execute_script("window.station.frameAges.splice(0)")
            frames0 = driver.execute_script("return window.station.frames")
            seq0 = driver.execute_script("return window.station.lastFrame.seq")

            def collect() -> None:
                ages.extend(driver.execute_script("return window.station.frameAges.splice(0)"))

            t0 = time.monotonic()
            watching = _cpu_percent(station.pid, args.seconds, during=collect)
            elapsed = time.monotonic() - t0
            fps = (driver.execute_script("return window.station.frames") - frames0) / elapsed
            # the station numbers every frame it receives: the page sees how many it skipped
            arrived = (
                driver.execute_script("return window.station.lastFrame.seq") - seq0
            ) / elapsed
            collect()
            errors = console_errors(driver)
            driver.save_screenshot(str(logs / "station_two_drones.png"))
    finally:
        for proc in reversed(procs):
            proc.send_signal(2)
        for proc in reversed(procs):
            try:
                proc.wait(20)
            except subprocess.TimeoutExpired:
                proc.kill()
    latency = percentiles(ages)
    print_table(
        f"Ground station with two simulated drones ({os.cpu_count()} cores; 100 % = one core)",
        ["page", "station CPU %", "frames/s at station", "drawn", "latency p50 ms", "p90", "max"],
        [
            ["none", idle, "-", "-", "-", "-", "-"],
            [
                "drone1 frontal",
                watching,
                arrived,
                fps,
                latency.get("p50_ms", float("nan")),
                latency.get("p90_ms", float("nan")),
                latency.get("max_ms", float("nan")),
            ],
        ],
    )
    if errors:
        print(f"console errors: {errors}")
    write_results(
        "station",
        {
            "seconds": args.seconds,
            "drones": list(DRONES),
            "station_cpu_percent_no_page": idle,
            "station_cpu_percent_watching_video": watching,
            "frames_per_second_at_station": arrived,
            "frames_per_second_drawn": fps,
            "video_latency": latency,
            "console_errors": errors,
        },
    )
    return 1 if errors or not ages else 0


if __name__ == "__main__":
    sys.exit(main())
