"""Which SDK call and which app works on which backend: probe them, and write
docs/capabilities.md from what the probes and the opt-in flights recorded.

    python -m bench.capabilities probe --backend sim|px4|ardupilot|tello [--px4 T] [--ardupilot T]
    python -m bench.capabilities render

``probe`` runs the backend's world-and-bridge graph (our simulated Iris, real PX4 SITL, real
ArduCopter SITL, our simulated Tello; the firmware as a free instance) and calls every public
call of ``DroneWrapper`` once on it, in a flight (connect, getters, cameras, parameters, the
command lease, arm/disarm, mode, take-off, the three setpoint kinds, stop, land), judging each
by its effect where it has one (the vehicle climbed, moved, held its altitude, landed); each
result is appended to bench/results/capabilities.jsonl with the backend's firmware version and
the date. The follow apps append theirs there too when the scenario flights run with
``DRONEWRAPPER_CAPABILITIES=bench/results/capabilities.jsonl`` (tests/scenario,
tests/sitl/test_follow_sitl.py). ``render`` keeps the newest result of each (call or app,
backend) and writes the matrix; the file is never edited by hand.
"""

from __future__ import annotations

import contextlib
import datetime
import json
import math
import os
import tempfile
import time
from collections.abc import Callable, Iterator
from pathlib import Path

from bench.common import RESULTS
from bench.fidelity import backend as iris_backend
from dronewrapper.runtime.arguments import CommandParser

REPO = Path(__file__).resolve().parents[1]
RECORDS = RESULTS / "capabilities.jsonl"
MATRIX = REPO / "docs" / "capabilities.md"
BACKENDS = {
    "sim": "our sim (Iris)",
    "px4": "PX4 SITL (SIH)",
    "px4_zenoh": "PX4 SITL (SIH) over its Zenoh",
    "ardupilot": "ArduCopter SITL",
    "tello": "our sim (Tello)",
}
CALLS = (
    "wait_for_connection", "is_connected", "get_state", "get_position", "get_velocity",
    "get_velocity_local", "get_yaw_rate", "get_orientation", "get_roll", "get_pitch", "get_yaw",
    "get_landed_state", "get_battery", "get_global_position", "is_flying", "get_image",
    "get_frontal_image", "get_ventral_image", "wait_for_image", "param_get", "param_set",
    "take_command", "release_command", "arm", "disarm", "set_mode", "takeoff",
    "wait_for_altitude", "wait_for", "set_cmd_vel", "set_cmd_pos", "set_cmd_mix",
    "stop_commanding", "home", "envelope", "set_envelope", "goto_local", "goto", "upload_mission",
    "start_mission", "mission_progress", "pause_mission", "resume_mission", "return_to_launch",
    "land", "wait_for_landed_state",
)  # fmt: skip
PARAM = {
    "sim": "MPC_XY_VEL_MAX",
    "px4": "MPC_XY_VEL_MAX",
    "px4_zenoh": "MPC_XY_VEL_MAX",
    "ardupilot": "WP_SPD",
    "tello": "",
}
HOLD_MODE = {
    "sim": "AUTO.LOITER",
    "px4": "AUTO.LOITER",
    "px4_zenoh": "AUTO.LOITER",
    "ardupilot": "GUIDED",
    "tello": "",
}
READY_S = 180.0


def record(entry: dict, path: Path = RECORDS) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    with open(path, "a") as out:
        out.write(json.dumps(entry) + "\n")


@contextlib.contextmanager
def tello_backend(workdir: Path) -> Iterator[tuple[str, str]]:
    from dronewrapper_compose.launcher import Launcher
    from dronewrapper_compose.ports import free_port

    router = f"tcp/127.0.0.1:{free_port()}"
    address = f"127.0.0.{50 + os.getpid() % 150}"  # a loopback address of its own: UDP 8889
    with open(workdir / "tello-graph.log", "w") as log:
        launcher = Launcher.from_file(
            REPO / "compose" / "sim_tello.yaml",
            router=router,
            variables={"scenario": "empty", "address": address},
            out=log,
        )
        try:
            launcher.start()
            yield router, "dronewrapper_sim Tello (ours)"
        finally:
            launcher.stop()


class Probe:
    """Calls and judges, one record each."""

    def __init__(self, backend: str, version: str) -> None:
        self.backend = backend
        self.version = version
        self.date = datetime.date.today().isoformat()
        self.results: dict[str, str] = {}

    def check(self, call: str, action: Callable[[], object], judge=lambda _v: "") -> object:
        """Run ``action``; ``judge(value)`` returns "" when its effect is right, else why."""
        try:
            value = action()
            problem = judge(value)
            result = "ok" if not problem else f"no effect: {problem}"
        except Exception as exc:  # every failure is a result to record
            value = None
            result = f"{type(exc).__name__}: {exc}".splitlines()[0][:160]
        self.results[call] = result
        record(
            {
                "kind": "call",
                "call": call,
                "backend": self.backend,
                "firmware": self.version,
                "date": self.date,
                "result": result,
            }
        )
        print(f"  {call:24s} {result}")
        return value


def _finite(value) -> str:
    try:
        values = [float(v) for v in (value if hasattr(value, "__len__") else [value])]
    except (TypeError, ValueError):
        return f"not numbers: {value!r}"
    return "" if all(math.isfinite(v) for v in values) else f"not finite: {value!r}"


def probe(drone, backend: str, version: str) -> Probe:
    p = Probe(backend, version)
    p.check("wait_for_connection", lambda: drone.wait_for_connection(READY_S))
    p.check("is_connected", drone.is_connected, lambda v: "" if v else "False")
    p.check("get_state", drone.get_state, lambda v: "" if v.connected else "not connected")

    def has(getter) -> bool:
        try:
            getter()
            return True
        except Exception:
            return False

    with contextlib.suppress(Exception):  # telemetry that follows the GPS fix: give it time
        drone.wait_for(lambda: has(drone.get_global_position), 45.0, "a global position")
    for name in ("get_position", "get_velocity", "get_velocity_local", "get_yaw_rate",
                 "get_orientation", "get_roll", "get_pitch", "get_yaw", "get_battery",
                 "get_global_position"):  # fmt: skip
        p.check(name, getattr(drone, name), _finite)
    p.check("get_landed_state", drone.get_landed_state, _finite)
    p.check("is_flying", drone.is_flying, lambda v: "flying on the ground" if v else "")
    p.check("wait_for_image", lambda: drone.wait_for_image("frontal", 30.0))
    p.check(
        "get_image", lambda: drone.get_image("frontal"), lambda v: "" if v is not None else "None"
    )
    for name, camera in (("get_frontal_image", "frontal"), ("get_ventral_image", "ventral")):
        with contextlib.suppress(Exception):  # the first frame of a camera asked for now
            drone.wait_for_image(camera, 10.0)
        p.check(name, getattr(drone, name), lambda v: "" if getattr(v, "size", 0) else "empty")
    param = PARAM[backend]
    value = p.check("param_get", lambda: drone.param_get(param or "SPEED"), _finite)
    p.check(
        "param_set", lambda: drone.param_set(param or "SPEED", value if value is not None else 1.0)
    )
    p.check("take_command", lambda: drone.take_command())
    p.check("release_command", lambda: drone.release_command())
    p.check("arm", lambda: _retry(drone.arm, 60.0))
    p.check("disarm", drone.disarm)
    p.check("set_mode", lambda: drone.set_mode(HOLD_MODE[backend] or "AUTO.LOITER"))
    p.check("takeoff", lambda: _retry(lambda: drone.takeoff(2.5, timeout=40.0), READY_S))
    p.check("wait_for_altitude", lambda: drone.wait_for_altitude(2.5, timeout=20.0, tolerance=0.3))
    p.check("wait_for", lambda: drone.wait_for(lambda: drone.is_flying(), timeout=5.0))

    def position():
        try:
            return [float(v) for v in drone.get_position()]
        except Exception:  # no position: the effects below read as not reached
            return [math.nan, math.nan, math.nan]

    def fly_for(seconds: float, action):
        def run():
            action()
            time.sleep(seconds)

        return run

    start = position()
    p.check(
        "set_cmd_vel",
        fly_for(3.0, lambda: drone.set_cmd_vel(vz=0.5)),
        lambda _v: "" if position()[2] - start[2] >= 0.8 else "did not climb 0.8 m in 3 s",
    )
    here = position()
    p.check(
        "set_cmd_pos",
        fly_for(8.0, lambda: drone.set_cmd_pos(here[0] + 2.0, here[1], here[2])),
        lambda _v: "" if abs(position()[0] - here[0] - 2.0) < 0.3 else "not within 0.3 m",
    )
    z = position()[2]
    p.check(
        "set_cmd_mix",
        fly_for(4.0, lambda: drone.set_cmd_mix(vx=0.5, z=z)),
        lambda _v: "" if abs(position()[2] - z) < 0.3 else "altitude not held within 0.3 m",
    )
    p.check("stop_commanding", drone.stop_commanding)
    probe_actions(p, drone, position)
    p.check("land", lambda: drone.land(timeout=90.0))
    p.check("wait_for_landed_state", lambda: drone.wait_for_landed_state(1, timeout=30.0))
    return p


def probe_actions(p: Probe, drone, position) -> None:
    """The envelope, go-to, mission and return calls (each one bridge operation), judged from
    the position the drone reports (ENU m from its local origin; home is where it armed)."""
    p.check("home", drone.home, lambda v: "" if math.isfinite(v.x) else "no local home")
    p.check("envelope", drone.envelope, lambda v: "" if v.max_altitude > 0 else "no ceiling")
    p.check(
        "set_envelope",
        lambda: drone.set_envelope(max_altitude=20.0, breach_action="return"),
        lambda v: "" if v.max_altitude == 20.0 else f"max_altitude {v.max_altitude}",
    )
    p.check(
        "goto_local",
        lambda: drone.goto_local(2.0, 0.0, 3.0, timeout=40.0, tolerance=0.5),
        lambda _v: "" if position()[2] > 2.0 else "not at 3 m",
    )

    def goto_north():
        from dronewrapper.geodesy import to_geodetic

        home = drone.home()
        if not math.isfinite(home.latitude):  # no GPS (the Tello): the call's own answer
            drone.goto(0.0, 0.0, 3.0, timeout=40.0, tolerance=0.5)
            return
        lat, lon = to_geodetic((home.latitude, home.longitude), 2.0, 2.0)
        drone.goto(lat, lon, 3.0, timeout=40.0, tolerance=0.5)

    p.check("goto", goto_north)
    square = [(2.0, 0.0, 3.0), (2.0, 2.0, 3.0), (0.0, 0.0, 3.0)]
    p.check("upload_mission", lambda: drone.upload_mission(square, frame="local"))
    p.check("start_mission", drone.start_mission)

    def progress():
        drone.wait_for(
            lambda: drone.mission_progress().reached is not None, 40.0, "an item reached"
        )
        return drone.mission_progress()

    p.check("mission_progress", progress, lambda v: "" if v.total == 3 else f"total {v.total}")
    p.check("pause_mission", drone.pause_mission)
    p.check("resume_mission", drone.resume_mission)
    with contextlib.suppress(Exception):
        drone.wait_for(lambda: drone.mission_progress().finished, 60.0, "the mission's end")
    p.check("return_to_launch", lambda: drone.return_to_launch(timeout=120.0))


def _retry(action, seconds: float):
    from dronewrapper.errors import CommandRefused

    give_up = time.time() + seconds
    while True:
        try:
            return action()
        except CommandRefused:
            if time.time() > give_up:
                raise
            time.sleep(2.0)


def run_probe(
    backend: str, px4: Path | None, ardupilot: Path | None, workdir: Path | None = None
) -> int:
    from dronewrapper import DroneWrapper

    with contextlib.ExitStack() as stack:
        if workdir is None:
            tmp = Path(stack.enter_context(tempfile.TemporaryDirectory(prefix=f"caps-{backend}-")))
        else:
            tmp = workdir
            tmp.mkdir(parents=True, exist_ok=True)
        if backend == "tello":
            router, version = stack.enter_context(tello_backend(tmp))
        else:
            router, version = stack.enter_context(iris_backend(backend, tmp, px4, ardupilot))
        print(f"{backend}: {version}")
        drone = DroneWrapper("drone", connect=router, timeout=READY_S)
        try:
            result = probe(drone, backend, version)
        finally:
            drone.close()
    failed = [c for c, r in result.results.items() if r != "ok"]
    print(f"{backend}: {len(result.results) - len(failed)}/{len(result.results)} calls ok")
    return 0


def latest(path: Path = RECORDS) -> dict[tuple[str, str, str], dict]:
    """The newest record of each (kind, call or app and scenario, backend)."""
    out: dict[tuple[str, str, str], dict] = {}
    if not path.is_file():
        return out
    for line in path.read_text().splitlines():
        if not line.strip():
            continue
        entry = json.loads(line)
        what = entry["call"] if entry["kind"] == "call" else f"{entry['app']} {entry['scenario']}"
        out[(entry["kind"], what, entry["backend"])] = entry
    return out


def _cell(entry: dict | None) -> str:
    if entry is None:
        return "not run"
    if entry["kind"] == "call":
        text = "ok" if entry["result"] == "ok" else f"**fails**: {entry['result']}"
    else:
        figures = f"centred {entry['centred']:.0%}, within distance {entry['within_distance']:.0%}"
        text = f"{'pass' if entry['passed'] else '**fails**'} ({figures})"
    return text.replace("|", "/")


def render(path: Path = RECORDS, out: Path = MATRIX) -> str:
    """Write the matrix from the records (and return it)."""
    records = latest(path)
    backends = list(BACKENDS)
    header = "| | " + " | ".join(BACKENDS[b] for b in backends) + " |"
    rule = "|---" * (len(backends) + 1) + "|"
    lines = [
        "# Capabilities: which call and which app works on which backend",
        "",
        "Generated by `python -m bench.capabilities render` from the recorded probes and flights",
        "(`bench/results/capabilities.jsonl`); never edited by hand. A cell says the newest",
        "result; the firmware versions and dates are listed below the tables.",
        "",
        "## SDK calls (`DroneWrapper`)",
        "",
        header,
        rule,
    ]
    for call in CALLS:
        cells = [_cell(records.get(("call", call, b))) for b in backends]
        lines.append(f"| `{call}` | " + " | ".join(cells) + " |")
    apps = sorted({what for kind, what, _ in records if kind == "app"})
    lines += ["", "## Apps (scenario flights judged from ground truth)", "", header, rule]
    for app in apps:
        cells = [_cell(records.get(("app", app, b))) for b in backends]
        lines.append(f"| {app} | " + " | ".join(cells) + " |")
    if not apps:
        lines.append("| (no flights recorded) |" + " not run |" * len(backends))
    lines += ["", "## Firmware and dates", ""]
    for b in backends:
        seen = sorted({(e["firmware"], e["date"]) for k, e in records.items() if k[2] == b})
        text = "; ".join(f"{fw}, {date}" for fw, date in seen) or "not run"
        lines.append(f"- {BACKENDS[b]}: {text}")
    text = "\n".join(lines) + "\n"
    out.write_text(text)
    print(f"wrote {out}")
    return text


def main(argv: list[str] | None = None) -> int:
    parser = CommandParser(description=__doc__.split("\n\n")[0])
    sub = parser.add_subparsers(dest="command", required=True)
    p = sub.add_parser("probe", help="call every SDK call on one backend and record the results")
    p.add_argument("--backend", choices=list(BACKENDS), required=True)
    p.add_argument("--px4", type=Path, default=os.environ.get("PX4_SITL_DIR") or None)
    p.add_argument("--ardupilot", type=Path, default=os.environ.get("AP_SITL_DIR") or None)
    p.add_argument("--workdir", type=Path, help="keep the firmware's and the graph's logs here")
    sub.add_parser("render", help="write docs/capabilities.md from the records")
    args = parser.parse_args(argv)
    if args.command == "probe":
        return run_probe(args.backend, args.px4, args.ardupilot, args.workdir)
    render()
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
