"""The MAVLink bridge and the PX4 Zenoh bridge side by side on one PX4 SIH run.

One ``px4_sitl_zenoh`` PX4 (``PX4_SITL_DIR``; its zenoh module on, its MAVLink onboard link up)
is bridged twice at once: bridge_mavlink in namespace ``mav`` on its onboard link, and
bridge_px4_zenoh in namespace ``zen`` on the router PX4 dials (tcp/127.0.0.1:7447). An SDK app
flies it through ``zen`` (take-off, then a slow forward turn) while an observer measures, over
``--seconds``:

* pose age: from the moment one estimator sample (``vehicle_local_position``, matched by its
  exact x, y, z) first arrives on this machine over PX4's Zenoh, to the moment each bridge's pose
  of it reaches the observer (ms; PX4's MAVLink module sends the same values later, at the rate
  the bridge asked);
* pose rate at the observer (Hz), and PX4's own vehicle_local_position rate;
* bridge CPU: each bridge process's user + system time over the window (% of one core).

The setpoint -> firmware delay is not measured: PX4 reports a setpoint's arrival nowhere (a
command's ack, the one echo, is not a setpoint's, and a command through the MAVLink bridge in
OFFBOARD would make it a second commander).

Run in a network namespace of its own (PX4 dials a fixed port)::

    unshare -rn sh -c 'ip link set lo up && PX4_SITL_DIR=... python -m bench.px4_zenoh_side_by_side'

Writes bench/results/px4_zenoh_side_by_side.json.
"""

from __future__ import annotations

import os
import sys
import tempfile
import threading
import time
from pathlib import Path

from bench.common import cpu_seconds, percentiles, print_table, write_results
from dronewrapper import DroneWrapper
from dronewrapper.errors import CommandRefused, NotConnected
from dronewrapper.msgs import registry
from dronewrapper.runtime.arguments import CommandParser, first_line
from dronewrapper.runtime.node import Node
from dronewrapper.runtime.options import DEFAULT_ROUTER, ZenohOptions
from dronewrapper_bridge_px4_zenoh import topics
from dronewrapper_compose.launcher import Launcher
from dronewrapper_ros2_codec import cdr
from dronewrapper_sim.external.firmware import px4_sih

REPO = Path(__file__).resolve().parents[1]
NAMESPACES = ("mav", "zen")
ROW_KEYS = (
    "pose_rate_hz",
    "pose_age_p50_ms",
    "pose_age_p90_ms",
    "cpu_percent",
)


class Observer:
    """Arrival times of PX4's raw estimator samples and of each bridge's poses of them."""

    def __init__(self, node: Node) -> None:
        self.first: dict[tuple[float, float, float], float] = {}
        self.raw_times: list[float] = []
        self.poses: dict[str, list[tuple[float, tuple[float, float, float]]]] = {
            ns: [] for ns in NAMESPACES
        }
        self.lock = threading.Lock()
        node.session.declare_subscriber("0/fmu/out/vehicle_local_position/**", self.on_raw)
        for ns in NAMESPACES:
            node.subscribe(
                registry.LOCAL_POSE, self.pose_handler(ns), key=registry.LOCAL_POSE.key(ns)
            )

    def on_raw(self, sample) -> None:
        now = time.monotonic()
        value = cdr.decode(topics.LOCAL_POSITION.type_name, sample.payload.to_bytes())
        with self.lock:
            self.raw_times.append(now)
            self.first.setdefault((value["x"], value["y"], value["z"]), now)

    def pose_handler(self, ns: str):
        def on_pose(pose) -> None:
            p = pose.pose.position
            with self.lock:
                self.poses[ns].append((time.monotonic(), (p.y, p.x, -p.z)))  # ENU -> NED

        return on_pose

    def window(self, since: float, until: float) -> dict[str, dict[str, float]]:
        with self.lock:
            raw = [t for t in self.raw_times if since <= t <= until]
            figures = {"px4_zenoh_raw": {"rate_hz": rate(raw)}}
            for ns, poses in self.poses.items():
                inside = [(t, key) for t, key in poses if since <= t <= until]
                ages = [t - self.first[key] for t, key in inside if key in self.first]
                figures[ns] = {
                    "pose_rate_hz": rate([t for t, _ in inside]),
                    "matched": len(ages) / max(len(inside), 1),
                    **{f"pose_age_{k}": v for k, v in percentiles(ages).items()},
                }
        return figures


def rate(times: list[float]) -> float:
    return (len(times) - 1) / (times[-1] - times[0]) if len(times) > 1 else 0.0


def take_off(drone: DroneWrapper, height: float, wait_s: float = 90.0) -> None:
    deadline = time.monotonic() + wait_s
    while True:
        try:
            drone.takeoff(h=height, timeout=40)
            return
        except (NotConnected, CommandRefused) as exc:
            if time.monotonic() > deadline:
                raise
            print(f"take-off not yet: {exc}", flush=True)
            time.sleep(2.0)


def measure(seconds: float, instance: int, workdir: Path) -> dict[str, object]:
    build = Path(os.environ["PX4_SITL_DIR"])
    log = open(workdir / "graphs.log", "w")  # noqa: SIM115 (closed below)
    zen = Launcher.from_file(REPO / "compose" / "px4_zenoh.yaml", namespace="zen", out=log)
    mav = Launcher.from_file(
        REPO / "compose" / "px4_sitl.yaml",
        namespace="mav",
        start_router=False,
        variables={"onboard_port": str(14540 + instance)},
        out=log,
    )
    zen.start()
    mav.start()
    bridges = {"zen": zen.children[0].proc.pid, "mav": mav.children[0].proc.pid}
    options = ZenohOptions(mode="client", connect=[DEFAULT_ROUTER])
    node = Node("observer", options, handle_signals=False, direct_callbacks=True)
    env = {"PX4_PARAM_ZENOH_ENABLE": "1"}
    try:
        with px4_sih(build, workdir, instance=instance, env=env) as firmware:
            observer = Observer(node)
            with DroneWrapper("zen", DEFAULT_ROUTER, timeout=90, land_on_exit=True) as drone:
                take_off(drone, 2.5)
                drone.set_cmd_vel(vx=0.5, az=0.3)
                time.sleep(1.0)
                cpu0 = {ns: cpu_seconds(pid) for ns, pid in bridges.items()}
                since = time.monotonic()
                time.sleep(seconds)
                until = time.monotonic()
                cpu = {
                    ns: (cpu_seconds(pid) - cpu0[ns]) / (until - since)
                    for ns, pid in bridges.items()
                }
                drone.set_cmd_vel()
                drone.land()
            figures = observer.window(since, until)
            for ns in NAMESPACES:
                figures[ns]["cpu_percent"] = 100.0 * cpu[ns]
            return {"firmware": firmware.version, "seconds": seconds, "figures": figures}
    finally:
        node.close()
        mav.stop()
        zen.stop()
        log.close()


def main(argv: list[str] | None = None) -> int:
    parser = CommandParser(description=first_line(__doc__))
    parser.add_argument("--seconds", type=float, default=15.0, help="measurement window (s)")
    parser.add_argument("--instance", type=int, default=1, help="PX4's instance (-i N)")
    parser.add_argument("--workdir", default="", help="keep PX4's and the graphs' logs here")
    args = parser.parse_args(argv)
    with tempfile.TemporaryDirectory() as tmp:
        workdir = Path(args.workdir or tmp)
        workdir.mkdir(parents=True, exist_ok=True)
        result = measure(args.seconds, args.instance, workdir)
    figures = result["figures"]
    rows = []
    for ns, name in (("mav", "bridge_mavlink"), ("zen", "bridge_px4_zenoh")):
        f = {key: float("nan") for key in ROW_KEYS} | figures[ns]
        rows.append(
            [
                name,
                f"{f['pose_rate_hz']:.0f}",
                f"{f['pose_age_p50_ms']:.1f}",
                f"{f['pose_age_p90_ms']:.1f}",
                f"{f['cpu_percent']:.1f}",
            ]
        )
    print_table(
        f"{result['firmware']}, one SIH run ({figures['px4_zenoh_raw']['rate_hz']:.0f} Hz "
        "vehicle_local_position on PX4's Zenoh)",
        ["bridge", "pose Hz", "age p50 ms", "age p90 ms", "CPU %"],
        rows,
    )
    write_results("px4_zenoh_side_by_side", result)
    return 0


if __name__ == "__main__":
    sys.exit(main())
