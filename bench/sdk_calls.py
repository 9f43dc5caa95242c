"""SDK benchmark: getter call time, and time from ``set_cmd_vel`` to the MAVLink packet.

Runs a loopback Zenoh router (in this process), the real bridge_mavlink (a child process) and a
fake autopilot (pymavlink over real UDP, in this process: heartbeats, SYS_STATUS,
LOCAL_POSITION_NED, ATTITUDE), then a DroneWrapper in client mode, as a laptop app would be.

* Getters: time per call of each getter (target: microseconds; they read the newest message
  already received, no network round trip). ``get_frontal_image`` returns a copy of a 320x240
  frame (the paper's camera size).
* Command latency: from the call of ``set_cmd_vel`` to the matching
  SET_POSITION_TARGET_LOCAL_NED datagram arriving at the fake autopilot's UDP socket (SDK
  encode -> Zenoh -> router -> bridge validation/frame conversion -> MAVLink over UDP). Each
  sample carries a distinct yaw rate so the packet is matched exactly, not a repetition.

    python -m bench.sdk_calls [--samples 300] [--calls 20000]
"""

from __future__ import annotations

import os
import random
import socket
import subprocess
import sys
import threading
import time
import timeit

import numpy as np

from bench.common import LoopbackRouter, percentiles, print_table, stop_process, write_results
from dronewrapper import DroneWrapper
from dronewrapper.errors import Timeout
from dronewrapper.msgs import Image, registry
from dronewrapper.runtime import Node, ZenohOptions
from dronewrapper.runtime.arguments import CommandParser, first_line
from dronewrapper_compose.ports import free_port

os.environ.setdefault("MAVLINK20", "1")
from pymavlink import mavutil

NS = "bench_sdk"


class FakeAutopilot:
    """Just enough of a PX4 on UDP: heartbeats, battery and pose out, setpoints in (timestamped)."""

    def __init__(self, port: int) -> None:
        self.mav = mavutil.mavlink_connection(
            f"udpout:127.0.0.1:{port}", source_system=1, source_component=1
        )
        self.stop = threading.Event()
        self.received: list[tuple[float, float]] = []  # (perf_counter, yaw_rate NED)
        self.cond = threading.Condition()
        self.threads = [
            threading.Thread(target=self._send_loop, daemon=True),
            threading.Thread(target=self._recv_loop, daemon=True),
        ]
        for t in self.threads:
            t.start()

    def _send_loop(self) -> None:
        m = self.mav.mav
        boot = time.monotonic()
        tick = 0
        while not self.stop.wait(0.02):
            ms = int((time.monotonic() - boot) * 1000)
            if tick % 25 == 0:
                m.heartbeat_send(2, 12, 1 | 128 * 0, 3 << 16, 3)  # quadrotor, PX4, POSCTL
                m.extended_sys_state_send(0, 1)  # on ground
                # battery: 12.4 V, 1.0 A, 90 % (the SDK connects once every getter's stream is in)
                m.sys_status_send(0, 0, 0, 500, 12400, 100, 90, 0, 0, 0, 0, 0, 0)
            m.local_position_ned_send(ms, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0)
            m.attitude_send(ms, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0)
            tick += 1

    def _recv_loop(self) -> None:
        while not self.stop.is_set():
            msg = self.mav.recv_match(
                type="SET_POSITION_TARGET_LOCAL_NED", blocking=True, timeout=0.2
            )
            if msg is None:
                continue
            now = time.perf_counter()
            with self.cond:
                self.received.append((now, msg.yaw_rate))
                self.cond.notify_all()

    def wait_for_yaw_rate(self, value: float, since: int, timeout: float) -> float | None:
        """perf_counter time of the first packet (index >= since) with this yaw rate."""
        deadline = time.perf_counter() + timeout
        with self.cond:
            while True:
                for t, rate in self.received[since:]:
                    if abs(rate - value) < 1e-5:
                        return t
                remaining = deadline - time.perf_counter()
                if remaining <= 0:
                    return None
                self.cond.wait(remaining)

    def close(self) -> None:
        self.stop.set()
        for t in self.threads:
            t.join(2)
        self.mav.close()


def time_getters(drone: DroneWrapper, calls: int) -> list[tuple[str, float]]:
    getters = {
        "get_position": drone.get_position,
        "get_velocity": drone.get_velocity,
        "get_orientation": drone.get_orientation,
        "get_yaw": drone.get_yaw,
        "get_yaw_rate": drone.get_yaw_rate,
        "get_landed_state": drone.get_landed_state,
        "get_state": drone.get_state,
        "is_connected": drone.is_connected,
        "get_frontal_image (320x240)": drone.get_frontal_image,
    }
    rows = []
    for name, fn in getters.items():
        n = calls if "image" not in name else max(200, calls // 20)
        best = min(timeit.repeat(fn, number=n, repeat=3)) / n
        rows.append((name, best * 1e6))
    return rows


def time_commands(drone: DroneWrapper, autopilot: FakeAutopilot, samples: int):
    latencies, call_times, lost = [], [], 0
    for i in range(samples):
        az = 0.001 * (i + 1)  # distinct per sample; NED yaw rate is -az
        since = len(autopilot.received)
        t0 = time.perf_counter()
        drone.set_cmd_vel(az=az)
        call_times.append(time.perf_counter() - t0)
        arrived = autopilot.wait_for_yaw_rate(-az, since, timeout=2.0)
        if arrived is None:
            lost += 1
        else:
            latencies.append(arrived - t0)
        time.sleep(random.uniform(0.005, 0.03))
    return latencies, call_times, lost


def main(argv: list[str] | None = None) -> int:
    parser = CommandParser(description=first_line(__doc__))
    parser.add_argument("--samples", type=int, default=300)
    parser.add_argument("--calls", type=int, default=20000)
    args = parser.parse_args(argv)

    router = LoopbackRouter()
    endpoint = router.endpoint
    udp_port = free_port(socket.SOCK_DGRAM)
    router.start()
    bridge = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "dronewrapper_bridge_mavlink",
            "--connect",
            endpoint,
            "--namespace",
            NS,
            "--name",
            "bridge_mavlink",
            "--set",
            f"connection=udpin:127.0.0.1:{udp_port}",
            "--log-level",
            "WARNING",
        ],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    autopilot = FakeAutopilot(udp_port)
    camera = Node(
        "bench_camera",
        ZenohOptions(mode="peer", connect=[endpoint], namespace=NS),
        handle_signals=False,
    )
    try:
        with DroneWrapper(NS, endpoint, timeout=60) as drone:
            pub = camera.publisher(registry.IMAGE_RAW, camera="cam_frontal")
            pixels = np.random.default_rng(0).integers(0, 255, (240, 320, 3), np.uint8)
            frame = Image(height=240, width=320, step=960, data=pixels.tobytes())
            for _ in range(40):  # the camera is subscribed on first use: publish until it is in
                pub.put(frame)
                try:
                    drone.wait_for_image("frontal", timeout=0.25)
                    break
                except Timeout:
                    continue
            else:
                raise Timeout("the benchmark's frame never reached the SDK within 10 s")
            drone.wait_for(lambda: drone.inputs.pose.value is not None, 10, "pose")
            getters = time_getters(drone, args.calls)
            time_commands(drone, autopilot, 20)  # warm-up
            latencies, call_times, lost = time_commands(drone, autopilot, args.samples)
            drone.stop_commanding()
    finally:
        camera.close()
        autopilot.close()
        stop_process(bridge)
        router.stop(5)

    print_table("getter call time (best of 3)", ["getter", "us/call"], getters)
    lat = percentiles(latencies)
    calls = percentiles(call_times)
    print_table(
        "set_cmd_vel -> SET_POSITION_TARGET_LOCAL_NED at the autopilot's UDP socket",
        ["measure", "n", "p50 ms", "p90 ms", "p99 ms", "max ms"],
        [
            ("call -> MAVLink packet", lat["n"], *(lat.get(k, 0.0) for k in _PCT)),
            ("set_cmd_vel call itself", calls["n"], *(calls.get(k, 0.0) for k in _PCT)),
        ],
    )
    print(f"  lost (no packet within 2 s): {lost} of {args.samples}")
    write_results(
        "sdk",
        {
            "getters_us_per_call": dict(getters),
            "set_cmd_vel_to_mavlink": lat,
            "set_cmd_vel_call": calls,
            "lost": lost,
            "path": "SDK client -> loopback router -> bridge_mavlink (peer) -> UDP",
        },
    )
    return 0 if lost == 0 else 1


_PCT = ("p50_ms", "p90_ms", "p99_ms", "max_ms")

if __name__ == "__main__":
    raise SystemExit(main())
