"""bridge_mavlink latency and CPU: the bridge process between a Zenoh router and a MAVLink peer.

Runs the real bridge (``python -m dronewrapper_bridge_mavlink``) against a PX4 stand-in in this
process that plays PX4's onboard-link telemetry mix at PX4's rates (about 500 messages/s; see
reading/px4_sitl_behaviour.md) over loopback UDP, and measures:

* setpoint latency: a PositionTarget put on Zenoh -> the SET_POSITION_TARGET_LOCAL_NED
  datagram arriving at the UDP socket here (target p99 <= 5 ms);
* telemetry latency: a LOCAL_POSITION_NED datagram sent here -> the PoseStamped sample here;
* CPU share of one core used by the bridge process (utime + stime from /proc), idle
  (telemetry only) and while commanded at 30 Hz (target <= 15 %).

Both clocks are this machine's CLOCK_MONOTONIC, shared by the two processes.
Run: ``.venv/bin/python -m bench.bridge_latency [--seconds S]``; writes bench/results/bridge.json.
"""

from __future__ import annotations

import os
import socket
import subprocess
import sys
import threading
import time
from pathlib import Path

os.environ.setdefault("MAVLINK20", "1")

from pymavlink.dialects.v20 import common as mavlink2

from bench import common
from dronewrapper.msgs import registry
from dronewrapper.msgs.geometry import Vector3
from dronewrapper.msgs.mavros import FRAME_LOCAL_NED, MASK_VELOCITY, PositionTarget
from dronewrapper.runtime import Node, ZenohOptions
from dronewrapper.runtime.arguments import CommandParser, first_line
from dronewrapper_compose.ports import free_port

REPO = Path(__file__).resolve().parents[1]

# PX4 onboard link, messages per second (px4_sitl_behaviour.md), as (name, hz)
PX4_RATES = [
    ("ATTITUDE", 99),
    ("ATTITUDE_QUATERNION", 49),
    ("GLOBAL_POSITION_INT", 49),
    ("HIGHRES_IMU", 49),
    ("LOCAL_POSITION_NED", 30),
    ("ODOMETRY", 30),
    ("TIMESYNC", 10),
    ("ALTITUDE", 10),
    ("DISTANCE_SENSOR", 10),
    ("ATTITUDE_TARGET", 10),
    ("POSITION_TARGET_LOCAL_NED", 10),
    ("SERVO_OUTPUT_RAW", 10),
    ("VFR_HUD", 10),
    ("GPS_RAW_INT", 8),
    ("SYS_STATUS", 5),
    ("EXTENDED_SYS_STATE", 5),
    ("HEARTBEAT", 1),
]


class PX4StandIn:
    """Sends PX4's telemetry mix to the bridge and stamps every setpoint that arrives."""

    def __init__(self, bridge_port: int) -> None:
        self.sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self.sock.bind(("127.0.0.1", 0))
        self.sock.settimeout(0.1)
        self.dest = ("127.0.0.1", bridge_port)
        self.mav = mavlink2.MAVLink(None, srcSystem=1, srcComponent=1)
        self.parser = mavlink2.MAVLink(None)
        self.stop = threading.Event()
        self.lpn_sent: dict[int, float] = {}  # marker -> monotonic send time
        self.setpoint_arrivals: dict[int, float] = {}  # marker -> first arrival
        self.sent = 0
        self._seq = 0

    def _encode(self, name: str, t_ms: int, marker: int):
        m = self.mav
        if name == "ATTITUDE":
            return m.attitude_encode(t_ms, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0)
        if name == "ATTITUDE_QUATERNION":
            return m.attitude_quaternion_encode(t_ms, 0.877, 0.0, 0.0, 0.479, 0.0, 0.0, 0.0)
        if name == "GLOBAL_POSITION_INT":
            return m.global_position_int_encode(t_ms, 473977420, 85455940, 493000, 5000, 0, 0, 0,
                                                9000)  # fmt: skip
        if name == "HIGHRES_IMU":
            return m.highres_imu_encode(t_ms * 1000, 0, 0, -9.8, 0, 0, 0, 0.2, 0, 0.4, 1013, 0,
                                        0, 25, 0)  # fmt: skip
        if name == "LOCAL_POSITION_NED":
            return m.local_position_ned_encode(t_ms, marker * 1e-3, 0.0, -5.0, 0.0, 0.0, 0.0)
        if name == "ODOMETRY":
            return m.odometry_encode(t_ms * 1000, 1, 12, 0, 0, -5, [1, 0, 0, 0], 0, 0, 0, 0, 0,
                                     0, [0.0] * 21, [0.0] * 21)  # fmt: skip
        if name == "TIMESYNC":
            return m.timesync_encode(0, t_ms * 1000)
        if name == "ALTITUDE":
            return m.altitude_encode(t_ms * 1000, 493, 493, 5, 5, 5, 5)
        if name == "DISTANCE_SENSOR":
            return m.distance_sensor_encode(t_ms, 10, 4000, 500, 0, 0, 25, 0)
        if name == "ATTITUDE_TARGET":
            return m.attitude_target_encode(t_ms, 0, [1, 0, 0, 0], 0, 0, 0, 0.5)
        if name == "POSITION_TARGET_LOCAL_NED":
            return m.position_target_local_ned_encode(t_ms, 1, 3064, 0, 0, -5, 0, 0, 0, 0, 0, 0,
                                                      0, 0)  # fmt: skip
        if name == "SERVO_OUTPUT_RAW":
            return m.servo_output_raw_encode(t_ms * 1000, 0, 1500, 1500, 1500, 1500, 0, 0, 0, 0)
        if name == "VFR_HUD":
            return m.vfr_hud_encode(0, 0, 90, 50, 493, 0)
        if name == "GPS_RAW_INT":
            return m.gps_raw_int_encode(t_ms * 1000, 3, 473977420, 85455940, 493000, 100, 100, 0,
                                        0, 10)  # fmt: skip
        if name == "SYS_STATUS":
            return m.sys_status_encode(0, 0, 0, 500, 12100, 1000, 80, 0, 0, 0, 0, 0, 0)
        if name == "EXTENDED_SYS_STATE":
            return m.extended_sys_state_encode(0, 2)
        if name == "HEARTBEAT":
            return m.heartbeat_encode(2, 12, 29 | 128, 6 << 16, 4)
        raise KeyError(name)

    def send_loop(self, duration: float) -> None:
        """Play the PX4 mix for ``duration`` s (each message at its own rate)."""
        t0 = time.monotonic()
        nexts = {name: t0 for name, _ in PX4_RATES}
        periods = dict(PX4_RATES)
        cache: dict[str, bytes] = {}  # packed once: keeps this sender light enough for the rates
        while not self.stop.is_set():
            now = time.monotonic()
            if now - t0 >= duration:
                return
            for name, at in nexts.items():
                if now >= at:
                    nexts[name] = at + 1.0 / periods[name]
                    marker = 0
                    if name == "LOCAL_POSITION_NED":
                        self._seq += 1
                        marker = self._seq
                    data = cache.get(name)
                    if data is None:  # only the marked LOCAL_POSITION_NED is packed each time
                        msg = self._encode(name, int((now - t0) * 1000), marker)
                        data = msg.pack(self.mav)
                        if not marker:
                            cache[name] = data
                    if marker:
                        self.lpn_sent[marker] = time.monotonic()
                    self.sock.sendto(data, self.dest)
                    self.sent += 1
            time.sleep(max(0.0, min(nexts.values()) - time.monotonic()))

    def recv_loop(self) -> None:
        while not self.stop.is_set():
            try:
                data, _ = self.sock.recvfrom(4096)
            except TimeoutError:
                continue
            at = time.monotonic()
            try:
                msgs = self.parser.parse_buffer(data) or []
            except Exception:
                continue
            for msg in msgs:
                if msg.get_type() == "SET_POSITION_TARGET_LOCAL_NED":
                    marker = round(msg.vy * 1000)  # ENU x (marker) -> NED y
                    self.setpoint_arrivals.setdefault(marker, at)


def main(argv: list[str] | None = None) -> int:
    parser = CommandParser(description=first_line(__doc__))
    parser.add_argument("--seconds", type=float, default=15.0, help="length of each phase")
    args = parser.parse_args(argv)

    router = common.started_router()
    endpoint = router.endpoint
    port = free_port(socket.SOCK_DGRAM)
    bridge = subprocess.Popen(
        [sys.executable, "-m", "dronewrapper_bridge_mavlink", "--connect", endpoint,
         "--set", f"connection=udpin:127.0.0.1:{port}", "--log-level", "WARNING",
         "--set", "commander_lost_timeout=3600"],
        cwd=REPO,
    )  # fmt: skip
    px4 = PX4StandIn(port)
    node = Node(
        "bench",
        ZenohOptions(connect=[endpoint], namespace="drone", name="bench"),
        handle_signals=False,
    )
    pose_arrivals: dict[int, float] = {}

    def on_pose(msg) -> None:
        pose_arrivals.setdefault(round(msg.pose.position.y * 1000), time.monotonic())

    node.subscribe(registry.LOCAL_POSE, on_pose)
    pub = node.publisher(registry.SETPOINT_RAW_LOCAL)
    receiver = threading.Thread(target=px4.recv_loop, daemon=True)
    receiver.start()
    results: dict[str, object] = {}
    try:
        # warm up: let the bridge connect and settle
        sender = threading.Thread(target=px4.send_loop, args=(3 * args.seconds + 10,), daemon=True)
        sender.start()
        deadline = time.monotonic() + 20
        while not pose_arrivals and time.monotonic() < deadline:
            time.sleep(0.1)
        if not pose_arrivals:
            print("the bridge published no pose", file=sys.stderr)
            return 1
        time.sleep(3.0)

        # phase 1: telemetry only (idle)
        c0, w0 = common.cpu_seconds(bridge.pid), time.monotonic()
        sent0 = px4.sent
        time.sleep(args.seconds)
        idle_cpu = (common.cpu_seconds(bridge.pid) - c0) / (time.monotonic() - w0)
        in_rate = (px4.sent - sent0) / (time.monotonic() - w0)

        # phase 2: commanded at 30 Hz (setpoint latency), telemetry latency throughout
        published: dict[int, float] = {}
        c0, w0 = common.cpu_seconds(bridge.pid), time.monotonic()
        marker = 0
        while time.monotonic() - w0 < args.seconds:
            marker += 1
            target = PositionTarget(
                coordinate_frame=FRAME_LOCAL_NED,
                type_mask=MASK_VELOCITY,
                velocity=Vector3(x=marker * 1e-3 % 10.0),
            )
            published[marker] = time.monotonic()
            pub.put(target)
            time.sleep(1.0 / 30.0)
        busy_cpu = (common.cpu_seconds(bridge.pid) - c0) / (time.monotonic() - w0)
        time.sleep(0.5)
        px4.stop.set()

        sp_lat = [
            px4.setpoint_arrivals[m] - t
            for m, t in published.items()
            if m in px4.setpoint_arrivals and m < 10000
        ]
        tel_lat = [pose_arrivals[m] - t for m, t in px4.lpn_sent.items() if m in pose_arrivals]
        sp = common.percentiles(sp_lat)
        tel = common.percentiles(tel_lat)
        results = {
            "setpoint_latency": {**sp, "published": len(published), "target_p99_ms": 5.0},
            "telemetry_latency": {**tel, "sent": len(px4.lpn_sent)},
            "cpu_share_one_core": {
                "idle_telemetry_only": round(idle_cpu, 4),
                "commanded_30hz": round(busy_cpu, 4),
                "target": 0.15,
                "mavlink_messages_per_s_in": round(in_rate, 1),
            },
        }
        common.print_table(
            "bridge_mavlink latency (ms)",
            ["path", "n", "p50", "p90", "p99", "max"],
            [
                ["setpoint Zenoh -> MAVLink", sp.get("n", 0), sp.get("p50_ms", 0.0),
                 sp.get("p90_ms", 0.0), sp.get("p99_ms", 0.0), sp.get("max_ms", 0.0)],
                ["telemetry MAVLink -> Zenoh", tel.get("n", 0), tel.get("p50_ms", 0.0),
                 tel.get("p90_ms", 0.0), tel.get("p99_ms", 0.0), tel.get("max_ms", 0.0)],
            ],
        )  # fmt: skip
        common.print_table(
            f"bridge_mavlink CPU (one core = 1.0; PX4 mix {in_rate:.0f} msg/s in)",
            ["phase", "cpu share", "target"],
            [["telemetry only", idle_cpu, 0.15], ["commanded 30 Hz", busy_cpu, 0.15]],
        )
        common.write_results("bridge", results)
    finally:
        px4.stop.set()
        node.close()
        common.stop_process(bridge)
        router.stop(5)
    return 0 if results else 1


if __name__ == "__main__":
    raise SystemExit(main())
