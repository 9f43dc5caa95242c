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

Then the setpoint -> firmware delay, through each bridge in turn (``--echo-seconds`` each):
PX4's zenoh module is told to publish the uORB ``trajectory_setpoint`` back
(``zenoh config add publisher``, PX4's own shell command, before the module starts), the topic
both paths end in: PX4's MAVLink receiver publishes each SET_POSITION_TARGET_LOCAL_NED there
while in OFFBOARD, its zenoh module each ``/fmu/in/trajectory_setpoint``. An app holds the
aircraft with position setpoints whose yaw steps by :data:`YAW_STEP` rad at
:data:`ECHO_RATE_HZ` (a sequence number in the heading), first through ``zen``, then, after
that app asked for AUTO.LOITER and stopped, through ``mav`` (OFFBOARD asked by it). The delay
of one setpoint: from the app's ``set_cmd_pos`` to the first echo carrying its yaw at the
observer, both on this machine's clock. The echo's own path (PX4's zenoh publisher, the
router) is the same for both bridges, so the difference between them is the bridges' and
their links'. The longest pause of the Zenoh bridge's ``offboard_control_mode`` stream where
it reaches the router is reported too (PX4 leaves OFFBOARD after 1 s without one).

Run in a network namespace of its own (PX4 dials a fixed port)::

    unshare -rn sh -c 'ip link set lo up && PX4_SITL_DIR=... python -m bench.px4_zenoh_side_by_side'

Writes bench/results/px4_zenoh_side_by_side.json.
"""

from __future__ import annotations

import itertools
import os
import subprocess
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
from dronewrapper_bridge_base.frames import yaw_enu_to_ned
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
    "setpoint_p50_ms",
    "setpoint_p90_ms",
    "setpoint_max_ms",
    "setpoint_echoed",
)
ECHO = "/fmu/out/trajectory_setpoint"  # PX4's uORB trajectory_setpoint, published back
ECHO_RATE_HZ = 5.0  # new yaw setpoints a second
YAW_STEP = 0.02  # rad between two successive setpoints' headings
YAW_VALUES = 10  # headings before one repeats (2 s at 5 Hz: far beyond any delay)
YAW_MATCH = 0.004  # rad: an echo carries a setpoint's yaw (float32, two conversions)


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


class SetpointEcho:
    """Setpoints sent with a heading that encodes their sequence number, and PX4's echo of them
    (its uORB ``trajectory_setpoint`` over its Zenoh, see module docstring)."""

    def __init__(self, node: Node) -> None:
        self.echoes: list[tuple[float, float]] = []  # (arrival, yaw NED rad)
        self.sent: dict[str, list[tuple[float, float]]] = {ns: [] for ns in NAMESPACES}
        self.written: list[float] = []  # arrivals of the Zenoh bridge's offboard_control_mode
        self.lock = threading.Lock()
        node.session.declare_subscriber(f"0{ECHO}/**", self.on_echo)
        node.session.declare_subscriber("0/fmu/in/offboard_control_mode/**", self.on_written)

    def on_written(self, _sample) -> None:
        with self.lock:
            self.written.append(time.monotonic())

    def longest_write_gap(self) -> float:
        """The longest pause (s) of the Zenoh bridge's offboard_control_mode stream, as it
        reached the router (PX4 leaves OFFBOARD after 1 s without one)."""
        with self.lock:
            times = list(self.written)
        return max((b - a for a, b in itertools.pairwise(times)), default=0.0)

    def on_echo(self, sample) -> None:
        now = time.monotonic()
        value = cdr.decode(topics.TRAJECTORY.type_name, sample.payload.to_bytes())
        with self.lock:
            self.echoes.append((now, value["yaw"]))

    def hold(self, drone: DroneWrapper, ns: str, seconds: float) -> None:
        """Hold where the aircraft is, a new heading every 1 / ECHO_RATE_HZ s, through ``ns``."""
        x, y, z = (float(v) for v in drone.get_position())
        period = 1.0 / ECHO_RATE_HZ
        start = time.monotonic()
        for k in range(int(seconds * ECHO_RATE_HZ)):
            yaw = YAW_STEP * (k % YAW_VALUES)
            now = time.monotonic()
            drone.set_cmd_pos(x, y, z, az=yaw)
            with self.lock:
                self.sent[ns].append((now, yaw_enu_to_ned(yaw)))
            time.sleep(max(0.0, start + (k + 1) * period - time.monotonic()))

    def delays(self, ns: str) -> dict[str, float]:
        """Percentiles of the delays (ms) of the setpoints sent through ``ns`` but the first
        (whose heading the mode change may have carried already), and the share of them
        echoed."""
        with self.lock:
            sent, echoes = list(self.sent[ns]), list(self.echoes)
        delays = []
        for at, yaw in sent[1:]:
            first = next(
                (t for t, echoed in echoes if t >= at and abs(echoed - yaw) < YAW_MATCH), None
            )
            if first is not None and first - at < YAW_VALUES / ECHO_RATE_HZ:
                delays.append(first - at)
        figures = {f"setpoint_{k}": v for k, v in percentiles(delays).items()}
        return {**figures, "setpoint_echoed": len(delays) / max(len(sent) - 1, 1)}


def zenoh_with_echo(build: Path, instance: int, workdir: Path) -> None:
    """PX4's zenoh module started with the uORB trajectory_setpoint among its publishers
    (PX4's shell: ``zenoh config add publisher``, then ``zenoh start``)."""
    client = str(build / "bin" / "px4-zenoh")
    deadline = time.monotonic() + 60.0
    add = ["config", "add", "publisher", ECHO, "trajectory_setpoint"]
    config = workdir / "px4" / "rootfs" / "zenoh" / "pub.csv"
    while not (config.is_file() and ECHO in config.read_text()):
        if time.monotonic() > deadline:
            raise RuntimeError(f"PX4's zenoh config has no {ECHO} after 60 s ({config})")
        subprocess.run([client, "--instance", str(instance), *add], capture_output=True)
        time.sleep(1.0)
    started = subprocess.run(
        [client, "--instance", str(instance), "start"], capture_output=True, text=True
    )
    if started.returncode != 0:
        raise RuntimeError(f"zenoh start failed: {started.stdout}{started.stderr}")


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


def measure(seconds: float, echo_seconds: float, instance: int, workdir: Path) -> dict[str, object]:
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
    try:
        with px4_sih(build, workdir, instance=instance) as firmware:  # its zenoh module off
            zenoh_with_echo(build, instance, workdir)
            observer = Observer(node)
            echo = SetpointEcho(node)
            with (
                DroneWrapper("zen", DEFAULT_ROUTER, timeout=90, land_on_exit=False) as via_zen,
                DroneWrapper("mav", DEFAULT_ROUTER, timeout=90, land_on_exit=True) as via_mav,
            ):
                take_off(via_zen, 2.5)
                via_zen.set_cmd_vel(vx=0.5, az=0.3)
                time.sleep(1.0)
                cpu0 = {ns: cpu_seconds(pid) for ns, pid in bridges.items()}
                since = time.monotonic()
                time.sleep(seconds)
                until = time.monotonic()
                cpu = {
                    ns: (cpu_seconds(pid) - cpu0[ns]) / (until - since)
                    for ns, pid in bridges.items()
                }
                try:
                    echo.hold(via_zen, "zen", echo_seconds)
                finally:
                    print(
                        f"zen: longest offboard_control_mode pause {echo.longest_write_gap():.2f} s"
                    )
                via_zen.stop_commanding()
                via_zen.set_mode("AUTO.LOITER")  # the zen bridge lets go: no hold stream of its own
                x, y, z = (float(v) for v in via_mav.get_position())
                via_mav.set_cmd_pos(x, y, z, az=0.0)
                via_mav.set_mode("OFFBOARD")  # primed by bridge_mavlink's stream of that setpoint
                echo.hold(via_mav, "mav", echo_seconds)
                via_mav.land()
            figures = observer.window(since, until)
            figures["zen"]["offboard_mode_longest_pause_s"] = echo.longest_write_gap()
            for ns in NAMESPACES:
                figures[ns]["cpu_percent"] = 100.0 * cpu[ns]
                figures[ns].update(echo.delays(ns))
            return {
                "firmware": firmware.version,
                "seconds": seconds,
                "echo_seconds": echo_seconds,
                "figures": figures,
            }
    finally:
        node.close()
        mav.stop()
        zen.stop()
        log.close()


def main(argv: list[str] | None = None) -> int:
    parser = CommandParser(description=first_line(__doc__))
    parser.add_argument("--seconds", type=float, default=15.0, help="measurement window (s)")
    parser.add_argument(
        "--echo-seconds", type=float, default=12.0, help="setpoint echo phase per bridge (s)"
    )
    parser.add_argument("--instance", type=int, default=1, help="PX4's instance (-i N)")
    parser.add_argument("--workdir", default="", help="keep PX4's and the graphs' logs here")
    args = parser.parse_args(argv)
    with tempfile.TemporaryDirectory() as tmp:
        workdir = Path(args.workdir or tmp)
        workdir.mkdir(parents=True, exist_ok=True)
        result = measure(args.seconds, args.echo_seconds, args.instance, workdir)
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
                f"{f['setpoint_p50_ms']:.1f}",
                f"{f['setpoint_p90_ms']:.1f}",
                f"{f['setpoint_max_ms']:.1f}",
                f"{f['setpoint_echoed']:.0%}",
            ]
        )
    print_table(
        f"{result['firmware']}, one SIH run ({figures['px4_zenoh_raw']['rate_hz']:.0f} Hz "
        "vehicle_local_position on PX4's Zenoh)",
        [
            "bridge",
            "pose Hz",
            "age p50 ms",
            "age p90 ms",
            "CPU %",
            "sp p50 ms",
            "sp p90",
            "sp max",
            "echoed",
        ],
        rows,
    )
    write_results("px4_zenoh_side_by_side", result)
    return 0


if __name__ == "__main__":
    sys.exit(main())
