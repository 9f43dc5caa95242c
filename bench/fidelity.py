"""Our simulator against the real thing: one command script flown on our sim, on real PX4 SITL
(SIH) and on real ArduCopter SITL, measured from ground truth, side by side.

The script (the SDK, as an app flies): take-off to 2.5 m; body velocity steps of 1 m/s on x, y
and z (each followed by a stop); a yaw-rate step of 1 rad/s; a 3 m position step; land; take off
again and kill the commander (the app stops streaming: the bridge holds, then asks the autopilot
to land). Every backend runs in our world (compose/sim_iris.yaml, compose/px4_sitl_world.yaml,
compose/ardupilot_sitl_world.yaml; the firmware as a free instance), so the figures all come from
``drone/sim/ground_truth``: velocities and the yaw rate are its differences over about 0.1 s,
in the body axes the vehicle had when each step was commanded.

Printed per axis: delay (to 10 %), rise time (10 -> 90 %), overshoot, settling time (within 10 %)
and steady-state error (bench/fidelity_metrics.py); the take-off (call to 90 % of 2.5 m), landing
(call to touchdown, z < 0.1 m) and failsafe (commander gone to the descent and to touchdown)
durations; and the ratio sim/real of each, marked where it lies outside 0.8-1.25. Saves the traces
and figures (bench/results/fidelity.json) and a PNG of the responses overlaid
(bench/results/fidelity.png).

    python -m bench.fidelity --px4 PX4_TREE --ardupilot ARDUPILOT_TREE [--only sim,px4]

(``PX4_SITL_DIR`` / ``AP_SITL_DIR`` are read when the flags are left out.) ``--only sim --reuse
FILE`` flies our sim alone and compares it with the firmware figures of an earlier run.
"""

from __future__ import annotations

import contextlib
import itertools
import json
import math
import os
import socket
import tempfile
import threading
import time
from collections.abc import Iterator
from pathlib import Path

from bench.common import RESULTS, print_table, write_results
from bench.fidelity_metrics import ratio, step_figures, within
from dronewrapper.runtime.arguments import CommandParser

REPO = Path(__file__).resolve().parents[1]
TAKEOFF_M = 2.5
STEPS = (("vx", 6.0), ("vy", 6.0), ("vz", 3.0), ("yaw_rate", 5.0))
REST_S = 4.0
POSITION_STEP_M = 3.0
POSITION_S = 10.0
DIFF_WINDOW_S = 0.1
READY_S = 180.0  # ArduCopter needs its GPS fix (~40 s) before it arms


def _free_port(kind: int = socket.SOCK_STREAM) -> int:
    from dronewrapper_compose.ports import free_port

    return free_port(kind)


@contextlib.contextmanager
def backend(
    name: str, workdir: Path, px4: Path | None, ardupilot: Path | None
) -> Iterator[tuple[str, str]]:
    """Run ``name``'s graph (and firmware); yields (router endpoint, firmware version)."""
    from dronewrapper.runtime.options import DEFAULT_ROUTER
    from dronewrapper_compose.launcher import Launcher
    from dronewrapper_sim.external.firmware import arducopter, px4_sih

    router = f"tcp/127.0.0.1:{_free_port()}"
    with contextlib.ExitStack() as stack:
        if name == "sim":
            graph, version = "sim_iris", "dronewrapper_sim (ours)"
            variables = {
                "scenario": "empty",
                "onboard_port": str(_free_port(socket.SOCK_DGRAM)),
                "gcs_port": str(_free_port(socket.SOCK_DGRAM)),
            }
        elif name == "px4":
            if px4 is None:
                raise SystemExit("px4: give --px4 PX4_TREE (or set PX4_SITL_DIR)")
            fw = stack.enter_context(px4_sih(px4, workdir))
            graph, version, variables = "px4_sitl_world", fw.version, dict(fw.variables)
        elif name == "px4_zenoh":  # PX4's zenoh-pico dials 7447: run in a namespace of its own
            if px4 is None:
                raise SystemExit("px4_zenoh: give --px4 PX4_SITL_ZENOH_BUILD (or PX4_SITL_DIR)")
            instance = int(os.environ.get("PX4_SITL_INSTANCE") or 1)
            zenoh_on = {"PX4_PARAM_ZENOH_ENABLE": "1"}
            fw = stack.enter_context(px4_sih(px4, workdir, instance=instance, env=zenoh_on))
            router = DEFAULT_ROUTER
            graph, version = "px4_zenoh_world", f"{fw.version} over its Zenoh"
            variables = {"truth_port": fw.variables["truth_port"]}
        else:
            if ardupilot is None:
                raise SystemExit("ardupilot: give --ardupilot TREE (or set AP_SITL_DIR)")
            fw = stack.enter_context(arducopter(ardupilot, workdir))
            graph, version, variables = "ardupilot_sitl_world", fw.version, dict(fw.variables)
        variables.setdefault("scenario", "empty")
        log = stack.enter_context(open(workdir / f"{name}-graph.log", "w"))
        launcher = Launcher.from_file(
            REPO / "compose" / f"{graph}.yaml", router=router, variables=variables, out=log
        )
        stack.callback(launcher.stop)
        launcher.start()
        yield router, version


class Truth:
    """Ground truth as it arrives: (stamp, x, y, z, yaw) in the world's ENU frame."""

    def __init__(self) -> None:
        self.rows: list[tuple[float, float, float, float, float]] = []
        self._lock = threading.Lock()

    def __call__(self, msg) -> None:
        from dronewrapper.rotations import rpy_from_quat

        p, q = msg.pose.position, msg.pose.orientation
        yaw = rpy_from_quat((q.x, q.y, q.z, q.w))[2]
        with self._lock:
            self.rows.append((msg.header.stamp, p.x, p.y, p.z, yaw))

    def snapshot(self) -> list[tuple[float, float, float, float, float]]:
        with self._lock:
            return list(self.rows)

    def latest(self) -> tuple[float, float, float, float, float]:
        with self._lock:
            return self.rows[-1]


def _wait(predicate, timeout: float, what: str) -> float:
    start = time.time()
    while time.time() - start < timeout:
        if predicate():
            return time.time()
        time.sleep(0.02)
    raise TimeoutError(f"{what}: not within {timeout:g} s")


def _takeoff(drone, deadline_s: float) -> float:
    """Take off to TAKEOFF_M (retrying while the autopilot is not ready); the call's time."""
    from dronewrapper.errors import CommandRefused, Timeout

    give_up = time.time() + deadline_s
    while True:
        called = time.time()
        try:
            drone.takeoff(TAKEOFF_M, timeout=40.0)
            return called
        except (CommandRefused, Timeout) as exc:
            if time.time() > give_up:
                raise
            print(f"  take-off refused ({exc}); again in 2 s")
            time.sleep(2.0)


def fly_script(drone, truth: Truth) -> dict[str, float]:
    """Fly the script; the wall-clock times of its events."""
    marks: dict[str, float] = {}
    marks["takeoff"] = _takeoff(drone, READY_S)
    drone.set_cmd_vel()
    time.sleep(3.0)
    for axis, seconds in STEPS:
        marks[axis] = time.time()
        drone.set_cmd_vel(**{"vx": 0.0, "vy": 0.0, "vz": 0.0, "az": 0.0} | {_arg(axis): 1.0})
        time.sleep(seconds)
        marks[f"{axis}_stop"] = time.time()
        drone.set_cmd_vel()
        time.sleep(REST_S)
    x, y, z = (float(v) for v in drone.get_position())
    marks["position"] = time.time()
    drone.set_cmd_pos(x + POSITION_STEP_M, y, z)
    time.sleep(POSITION_S)
    marks["position_stop"] = time.time()
    marks["land"] = time.time()
    drone.land(timeout=90.0)
    marks["landed_disarmed"] = time.time()
    time.sleep(2.0)
    marks["takeoff2"] = _takeoff(drone, 60.0)
    drone.set_cmd_vel()
    time.sleep(3.0)
    marks["kill"] = time.time()
    drone.stop_commanding()
    _wait(lambda: truth.latest()[3] < 0.1, 90.0, "touchdown after the commander was killed")
    marks["end"] = time.time() + 1.0
    time.sleep(1.0)
    return marks


def _arg(axis: str) -> str:
    return "az" if axis == "yaw_rate" else axis


def _unwrap(values: list[float]) -> list[float]:
    out, offset = [values[0]], 0.0
    for a, b in itertools.pairwise(values):
        d = b - a
        if d > math.pi:
            offset -= 2 * math.pi
        elif d < -math.pi:
            offset += 2 * math.pi
        out.append(b + offset)
    return out


def derivative(t: list[float], y: list[float], window_s: float = DIFF_WINDOW_S):
    """Central differences over about ``window_s``: (t, dy/dt)."""
    out_t, out_v = [], []
    j0 = j1 = 0
    for i, ti in enumerate(t):
        while t[j0] < ti - window_s / 2:
            j0 += 1
        while j1 + 1 < len(t) and t[j1 + 1] <= ti + window_s / 2:
            j1 += 1
        if t[j1] - t[j0] >= window_s / 2 and i > 0:
            out_t.append(ti)
            out_v.append((y[j1] - y[j0]) / (t[j1] - t[j0]))
    return out_t, out_v


def analyse(rows, marks: dict[str, float]) -> dict[str, dict]:
    """The traces and figures of one flight."""
    t = [r[0] for r in rows]
    x, y, z = ([r[k] for r in rows] for k in (1, 2, 3))
    yaw = _unwrap([r[4] for r in rows])
    tv, vxw = derivative(t, x)
    _, vyw = derivative(t, y)
    _, vz = derivative(t, z)
    _, wz = derivative(t, yaw)

    def at(ts, vs, when):
        return vs[min(range(len(ts)), key=lambda i: abs(ts[i] - when))]

    out: dict[str, dict] = {}
    for axis, _seconds in STEPS:
        start, stop = marks[axis], marks[f"{axis}_stop"]
        heading = at(t, yaw, start)
        c, s = math.cos(heading), math.sin(heading)
        series = {
            "vx": [c * a + s * b for a, b in zip(vxw, vyw, strict=True)],
            "vy": [-s * a + c * b for a, b in zip(vxw, vyw, strict=True)],
            "vz": vz,
            "yaw_rate": wz,
        }[axis]
        window = [
            (ti - start, v) for ti, v in zip(tv, series, strict=True) if start - 1 <= ti <= stop
        ]
        ts, vs = [w[0] for w in window], [w[1] for w in window]
        figures = step_figures(ts, vs, 0.0, 0.0, 1.0)
        out[axis] = {"t": ts, "y": vs, "figures": figures.as_dict()}
    start, stop = marks["position"], marks["position_stop"]
    x0, y0 = at(t, x, start), at(t, y, start)
    window = [
        (ti - start, math.hypot(xi - x0, yi - y0))
        for ti, xi, yi in zip(t, x, y, strict=True)
        if start - 1 <= ti <= stop
    ]
    ts, ds = [w[0] for w in window], [w[1] for w in window]
    out["position"] = {
        "t": ts,
        "y": ds,
        "figures": step_figures(ts, ds, 0.0, 0.0, POSITION_STEP_M).as_dict(),
    }

    def first(after: float, pred) -> float:
        return next(
            (ti - after for ti, zi in zip(t, z, strict=True) if ti >= after and pred(zi)), math.nan
        )

    hold_z = at(t, z, marks["kill"])
    out["durations"] = {
        "figures": {
            "takeoff_s": first(marks["takeoff"], lambda zi: zi >= 0.9 * TAKEOFF_M),
            "landing_s": first(marks["land"], lambda zi: zi < 0.1),
            "landing_disarmed_s": marks["landed_disarmed"] - marks["land"],
            "failsafe_descent_s": first(marks["kill"], lambda zi: zi < hold_z - 0.2),
            "failsafe_touchdown_s": first(marks["kill"], lambda zi: zi < 0.1),
        }
    }
    return out


def fly_backend(name: str, px4: Path | None, ardupilot: Path | None) -> dict:
    from dronewrapper import DroneWrapper
    from dronewrapper.msgs import registry

    with contextlib.ExitStack() as stack:
        tmp = Path(stack.enter_context(tempfile.TemporaryDirectory(prefix=f"fidelity-{name}-")))
        router, version = stack.enter_context(backend(name, tmp, px4, ardupilot))
        truth = Truth()
        drone = DroneWrapper("drone", connect=router, timeout=READY_S)
        try:
            drone.subscribe(registry.SIM_GROUND_TRUTH, truth)
            _wait(lambda: drone.is_connected() and truth.rows, READY_S, f"{name} ready")
            print(f"{name}: {version}: flying the script")
            marks = fly_script(drone, truth)
        finally:
            drone.close()
        return {"version": version, "marks": marks, **analyse(truth.snapshot(), marks)}


def table(results: dict[str, dict]) -> list[list]:
    names = list(results)
    reals = [n for n in names if n != "sim"]
    rows = []
    for section in ("vx", "vy", "vz", "yaw_rate", "position", "durations"):
        keys = results[names[0]][section]["figures"].keys()
        for key in keys:
            values = [results[n][section]["figures"][key] for n in names]
            row = [f"{section} {key}", *values]
            if "sim" in results:
                for real in reals:
                    r = ratio(
                        results["sim"][section]["figures"][key],
                        results[real][section]["figures"][key],
                    )
                    row.append(f"{r:.2f}{'' if within(r) else ' !'}" if math.isfinite(r) else "-")
            rows.append(row)
    return rows


def plot(results: dict[str, dict], path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    sections = ("vx", "vy", "vz", "yaw_rate", "position")
    fig, axes = plt.subplots(len(sections), 1, figsize=(8, 12), sharex=False)
    for ax, section in zip(axes, sections, strict=True):
        for name, res in results.items():
            ax.plot(res[section]["t"], res[section]["y"], label=name)
        ax.set_title(section)
        ax.set_xlabel("s after the command")
        ax.grid(True)
    axes[0].legend()
    fig.tight_layout()
    fig.savefig(path, dpi=80)
    print(f"wrote {path}")


def main(argv: list[str] | None = None) -> int:
    parser = CommandParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--px4", type=Path, default=os.environ.get("PX4_SITL_DIR") or None)
    parser.add_argument("--ardupilot", type=Path, default=os.environ.get("AP_SITL_DIR") or None)
    parser.add_argument("--only", default="sim,px4,ardupilot", help="backends, comma-separated")
    parser.add_argument(
        "--reuse",
        type=Path,
        metavar="FILE",
        help="take the backends not flown now from an earlier run's fidelity.json",
    )
    args = parser.parse_args(argv)
    flown = [n for n in args.only.split(",") if n]
    earlier = json.loads(args.reuse.read_text())["backends"] if args.reuse else {}
    results = {name: fly_backend(name, args.px4, args.ardupilot) for name in flown}
    for name, res in earlier.items():
        if name not in results:
            results[name] = res
            print(f"{name}: figures of an earlier run ({args.reuse})")
    names = [n for n in ("sim", "px4", "ardupilot") if n in results]
    results = {n: results[n] for n in names}
    reals = [n for n in names if n != "sim"]
    header = ["figure", *names, *(f"sim/{r}" for r in reals if "sim" in names)]
    print_table("fidelity: step responses and durations (ground truth)", header, table(results))
    RESULTS.mkdir(parents=True, exist_ok=True)
    plot(results, RESULTS / "fidelity.png")
    write_results("fidelity", {"backends": results})
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
