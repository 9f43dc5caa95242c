"""How the cost grows with the number of drones: N simulated Iris without cameras on one router.

For each N (1, 5, 10 and 20, then +10 until the knee or ``--max``) it starts ``compose/sim_fleet``
through ``dronewrapper up`` (its own process: the launcher holds the router), lets it settle,
and over ``--seconds`` measures:

* CPU (% of one core, ``/proc/PID/stat`` utime + stime) and memory (RSS) of every sim, every
  bridge and the router (the launcher process: the router, and a thread per child's log);
* each drone's pose age at one subscriber (``bench.pose_ages``: a process of its own, a client
  of the router, doing nothing else): its wall clock at arrival minus the pose's
  ``header.stamp``, p50/p99 per drone, and the slowest drone's pose rate;
* the SDK's fleet object (``dronewrapper.fleet.Fleet`` over all N drones, a process of its
  own, connected meanwhile) and its CPU; it receives the streams it reads (``state``,
  ``extended``, ``pose``, ``battery``; ``--fleet-streams all``: every getter's stream, eight
  a drone);

then, over another ``--seconds``, the probes (the poses' ages and rates again, meanwhile):

* the command round trip of the arming service (a disarm on the ground: answered, changes
  nothing), each drone in turn and each at most every 0.5 s, p50/p99 over all the calls;
* setpoint -> MAVLink: one more bridge in namespace ``probe``, against a PX4 stand-in in this
  process (``bench.bridge_latency``: PX4's whole telemetry mix, about 500 datagrams a second),
  commanded at 30 Hz, p99. The probes are instruments, not the fleet: their window is apart
  so that what they cost the machine is not counted against the fleet's poses;
* with ``--fly``, after the window: all N take off together through that ``Fleet`` (1.5 m),
  then land together, how many made it and how long each took.

``--per-process N`` runs N drones' sims and bridges in one process (the graph's
``per_process``; a process then counts as ``host``, its CPU and memory split evenly over its
drones). ``--busy`` keeps one core busy with an unrelated program (a Python ``while True``
loop) for the whole run, as a laptop doing other things.

The knee is the first N where the machine no longer keeps up: a drone's pose age p99 over
50 ms, a start that fails, or the processes' CPU over 90 % of the machine's cores. A plot of
the cost per drone against N goes to bench/results/fleet.png. Targets: bridge <= 2 % of a core
per drone at full telemetry, 80 MB per drone (sim + bridge); 30 drones each with pose age p99
<= 50 ms, with one core busy; cost flat per drone in N.

    nice -n 5 python -m bench.fleet [--seconds 10] [--max 60] [--counts 1 5 10 20]
        [--per-process N] [--busy] [--fly] [--fleet-streams read|all]

Size: one N's whole measurement (the fleet, the probes, the SDK's fleet, the flight) and its
report read in one place; the pose subscriber is bench.pose_ages and the plots are
bench.fleet_plot.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import threading
import time
from collections import defaultdict
from pathlib import Path

from bench.busy import busy_core
from bench.common import RESULTS, percentiles, print_table, stop_process, write_results
from bench.fleet_plot import per_drone, plot
from dronewrapper.msgs import registry
from dronewrapper.msgs.geometry import Vector3
from dronewrapper.msgs.mavros import FRAME_LOCAL_NED, MASK_VELOCITY, CommandBool, PositionTarget
from dronewrapper.runtime.arguments import CommandParser, first_line
from dronewrapper.runtime.errors import ServiceError, ServiceUnavailable
from dronewrapper_compose.ports import free_port

REPO = Path(__file__).resolve().parents[1]
TICKS = os.sysconf("SC_CLK_TCK")
PAGE = os.sysconf("SC_PAGE_SIZE")
POSE_AGE_P99_MS = 50.0
BRIDGE_SHARE_PER_DRONE = 2.0
MEMORY_PER_DRONE_MB = 80.0
MACHINE_BUSY = 0.9
ARMING_SPACING_S = 0.5
"""Calls of the arming service to one drone are at least this far apart (s)."""
"""The knee: the processes use more than this share of every core."""


# ---------------------------------------------------------------------------- processes


def cpu_seconds(pid: int) -> float:
    """User + system CPU seconds of a process so far (0 when it is gone)."""
    try:
        fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    except OSError:
        return 0.0
    return (int(fields[11]) + int(fields[12])) / TICKS


def rss_mb(pid: int) -> float:
    """Resident memory of a process (MB; 0 when it is gone)."""
    try:
        return int(Path(f"/proc/{pid}/statm").read_text().split()[1]) * PAGE / 1e6
    except OSError:
        return 0.0


ROLES = {"dronewrapper_sim": "sim", "dronewrapper.runtime.host": "host"}


def children_of(pid: int) -> dict[int, str]:
    """{pid: role} of the launcher's children: ``sim``, ``bridge`` or ``host`` (both, for
    several drones)."""
    found = {}
    for stat in Path("/proc").glob("[0-9]*/stat"):
        try:
            fields = stat.read_text().rsplit(")", 1)[1].split()
            cmdline = (stat.parent / "cmdline").read_bytes().decode().split("\0")
        except OSError:
            continue
        if int(fields[1]) != pid:
            continue
        module = cmdline[cmdline.index("-m") + 1] if "-m" in cmdline else ""
        found[int(stat.parent.name)] = ROLES.get(module, "bridge")
    return found


# ---------------------------------------------------------------------------- one fleet


def command(child: subprocess.Popen, line: str) -> dict[str, object]:
    """Send ``line`` to the pose subscriber (``bench.pose_ages``); its answer to ``stop``."""
    child.stdin.write(line + "\n")
    child.stdin.flush()
    return json.loads(child.stdout.readline()) if line == "stop" else {}


def arming_round_trips(session, names: list[str], until: float) -> tuple[list[float], int]:
    """Disarm requests (answered on the ground, change nothing) to each drone in turn, one
    drone at a time, each drone at most every :data:`ARMING_SPACING_S`: the bridge holds a
    command back until late duplicate acks of the previous one with the same id can have
    passed (``AckRouter.dedup_window``, 0.3 s), so calls closer together would measure that
    hold, not the round trip."""
    from dronewrapper.runtime.node import call_service

    rtts, failures = [], 0
    last: dict[str, float] = {}
    while time.monotonic() < until:
        for ns in names:
            wait = last.get(ns, -ARMING_SPACING_S) + ARMING_SPACING_S - time.monotonic()
            if wait > 0:
                time.sleep(wait)
            t0 = time.perf_counter()
            try:
                call_service(session, registry.ARMING, CommandBool(value=False), ns=ns, timeout=2)
                rtts.append(time.perf_counter() - t0)
            except (ServiceError, ServiceUnavailable):
                failures += 1
            last[ns] = time.monotonic()
            time.sleep(0.02)
    return rtts, failures


def setpoint_probe(endpoint: str, stop: threading.Event):
    """One more bridge (namespace ``probe``) against a PX4 stand-in here; returns the stand-in,
    the bridge process and a function that streams marked setpoints until ``stop``."""
    from bench.bridge_latency import PX4StandIn
    from dronewrapper.runtime import Node, ZenohOptions

    port = free_port("udp")
    bridge = subprocess.Popen(
        [sys.executable, "-m", "dronewrapper_bridge_mavlink", "--connect", endpoint,
         "--namespace", "probe", "--set", f"connection=udpin:127.0.0.1:{port}",
         "--log-level", "WARNING", "--set", "commander_lost_timeout=3600"],
        cwd=REPO,
    )  # fmt: skip
    px4 = PX4StandIn(port)
    threading.Thread(target=px4.recv_loop, daemon=True).start()
    threading.Thread(target=px4.send_loop, args=(3600.0,), daemon=True).start()
    options = ZenohOptions(mode="client", connect=[endpoint], namespace="probe", name="bench")
    node = Node("bench_probe", options, handle_signals=False)
    pub = node.publisher(registry.SETPOINT_RAW_LOCAL)
    published: dict[int, float] = {}

    def stream() -> None:
        marker = 0
        while not stop.is_set():
            marker += 1
            target = PositionTarget(coordinate_frame=FRAME_LOCAL_NED, type_mask=MASK_VELOCITY,
                                    velocity=Vector3(x=marker * 1e-3 % 10.0))  # fmt: skip
            published[marker] = time.monotonic()
            pub.put(target)
            stop.wait(1.0 / 30.0)

    def latencies() -> list[float]:
        arrivals = px4.setpoint_arrivals
        return [arrivals[m] - t for m, t in published.items() if m in arrivals and m < 10000]

    def close() -> None:
        px4.stop.set()
        node.close()
        stop_process(bridge, timeout_s=10)

    return stream, latencies, close


def hold_fleet(endpoint: str, count: int, seconds: float, fly: bool, streams: str) -> None:
    """In a child: open the SDK's fleet over every drone, hold it ``seconds``, print its CPU;
    with ``fly``, then take off all together and land all together, and print how it went.
    ``streams``: ``read`` (what this reads: the flight's streams and the battery) or ``all``."""
    from dronewrapper.fleet import Fleet

    names = [f"drone{i}" for i in range(1, count + 1)]  # not the setpoint probe's bridge
    chosen = None if streams == "all" else ["battery"]  # + state, extended, pose (flights)
    with Fleet.connect(names, connect=endpoint, timeout=120, cameras=(), streams=chosen) as fleet:
        print("ready", flush=True)
        c0, t0 = time.process_time(), time.monotonic()
        time.sleep(seconds)
        share = (time.process_time() - c0) / (time.monotonic() - t0)
        healthy = sum(info.healthy for info in fleet.online())
        print(json.dumps({"cpu_percent": 100 * share, "rss_mb": rss_mb(os.getpid()),
                          "healthy": healthy}), flush=True)  # fmt: skip
        flight: dict[str, object] = {}
        if fly and sys.stdin.readline().strip() == "fly":  # after the window's arming calls
            t0 = time.monotonic()
            up = fleet.takeoff(h=1.5, timeout=60)
            flight["takeoff_ok"], flight["takeoff_s"] = len(up.results()), time.monotonic() - t0
            flight["takeoff_failed"] = {k: str(v) for k, v in up.failed.items()}
            t0 = time.monotonic()
            down = fleet.land(timeout=90)
            flight["land_ok"], flight["land_s"] = len(down.results()), time.monotonic() - t0
            flight["land_failed"] = {k: str(v) for k, v in down.failed.items()}
        print(json.dumps(flight), flush=True)


def measure(
    count: int,
    seconds: float,
    settle: float,
    log_dir: Path,
    kind: str = "iris",
    per_process: int = 1,
    fly: bool = False,
    fleet_streams: str = "read",
) -> dict[str, object]:
    """Start a fleet of ``count`` drones, measure it, stop it."""

    from dronewrapper.runtime.node import open_session
    from dronewrapper.runtime.options import ZenohOptions

    endpoint = f"tcp/127.0.0.1:{free_port()}"
    log_path = log_dir / f"fleet_{count}.log"
    argv = [sys.executable, "-m", "dronewrapper", "up", "sim_fleet", "--router", endpoint,
            "--var", f"drones={count}", "--var", f"kind={kind}",
            "--var", f"per_process={per_process}"]  # fmt: skip
    out: dict[str, object] = {"drones": count, "kind": kind, "per_process": per_process,
                              "fleet_streams": fleet_streams}  # fmt: skip
    started = time.monotonic()
    with open(log_path, "w") as log:
        up = subprocess.Popen(argv, stdout=log, stderr=subprocess.STDOUT, cwd=REPO)
    stop, probe = threading.Event(), None
    session = ages = None
    try:
        while "all processes ready" not in log_path.read_text():
            if up.poll() is not None or time.monotonic() - started > 60 + 5 * count:
                out["error"] = f"the fleet did not start (see {log_path})"
                return out
            time.sleep(0.2)
        out["start_s"] = time.monotonic() - started
        names = [f"drone{i}" for i in range(1, count + 1)]
        session = open_session(ZenohOptions(mode="client", connect=[endpoint]))
        ages = subprocess.Popen([sys.executable, "-m", "bench.pose_ages", endpoint],
                                stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True,
                                cwd=REPO)  # fmt: skip
        if ages.stdout.readline().strip() != "ready":
            out["error"] = "the pose subscriber did not start"
            return out
        holder = subprocess.Popen(
            [sys.executable, "-m", "bench.fleet", "--hold", endpoint, str(count),
             str(seconds), "1" if fly else "0", fleet_streams], stdin=subprocess.PIPE,
            stdout=subprocess.PIPE, text=True, cwd=REPO,
        )  # fmt: skip
        if holder.stdout.readline().strip() != "ready":
            out["error"] = "the SDK's fleet did not connect"
            return out
        time.sleep(settle)
        pids = {**children_of(up.pid), up.pid: "router"}
        before = {pid: cpu_seconds(pid) for pid in pids}
        command(ages, "start")  # the fleet and its Fleet alone
        t0 = time.monotonic()
        time.sleep(seconds)
        elapsed = time.monotonic() - t0
        window = command(ages, "stop")
        usage: dict[str, list[float]] = defaultdict(list)
        memory: dict[str, list[float]] = defaultdict(list)
        for pid, role in pids.items():
            usage[role].append(100 * (cpu_seconds(pid) - before[pid]) / elapsed)
            memory[role].append(rss_mb(pid))
        sdk = json.loads(holder.stdout.readline())
        stream, setpoint_latencies, probe = setpoint_probe(endpoint, stop)  # the probes' window
        threading.Thread(target=stream, daemon=True).start()
        command(ages, "start")
        rtts, failures = arming_round_trips(session, names, time.monotonic() + seconds)
        probed = command(ages, "stop")
        stop.set()
        probe()
        probe = None
        if fly:  # all take off and land together; the poses' ages meanwhile
            command(ages, "start")
            holder.stdin.write("fly\n")
            holder.stdin.flush()
            sdk["flight"] = json.loads(holder.stdout.readline())
            sdk["flight"]["pose_age"] = command(ages, "stop")["all"]
        holder.stdin.close()
        holder.wait(30)
        hosts = usage.pop("host", None)
        if hosts is not None:  # a host's CPU and memory, split evenly over its drones
            usage["drone (sim+bridge)"] = [sum(hosts) / count] * count
            memory["drone (sim+bridge)"] = [sum(memory.pop("host")) / count] * count
        per_drone = {ns: window["per_drone"].get(ns, {"n": 0}) for ns in names}
        out.update(
            cpu_percent={role: sum(v) for role, v in usage.items()},
            cpu_percent_per_process={role: sum(v) / len(v) for role, v in usage.items()},
            rss_mb={role: sum(v) for role, v in memory.items()},
            rss_mb_per_process={role: sum(v) / len(v) for role, v in memory.items()},
            sdk_fleet=sdk,
            pose_age=per_drone,
            pose_age_worst_p99_ms=max(p.get("p99_ms", float("inf")) for p in per_drone.values()),
            pose_age_p50_ms=window["all"].get("p50_ms"),
            pose_rate_hz_min=min((window["rate_hz"].get(ns, 0.0) for ns in names), default=0),
            arming_rtt={**percentiles(rtts), "failures": failures},
            setpoint_to_mavlink=percentiles(setpoint_latencies()),
            probed_pose_age_worst_p99_ms=max(
                (p.get("p99_ms", float("inf")) for p in probed["per_drone"].values()),
                default=float("inf"),
            ),
            probed_pose_rate_hz_min=min(
                (probed["rate_hz"].get(ns, 0.0) for ns in names), default=0.0
            ),
            loadavg=os.getloadavg()[0],
        )
        return out
    finally:
        stop.set()
        if ages is not None:
            ages.stdin.close()
            ages.wait(10)
        if probe is not None:
            probe()
        if session is not None:
            session.close()
        stop_process(up, timeout_s=60 + count)


# ---------------------------------------------------------------------------- report


def knee_reason(result: dict[str, object]) -> str:
    """Why this N is past what the machine holds ("" if it holds it)."""
    if "error" in result:
        return str(result["error"])
    flight = result["sdk_fleet"].get("flight") or {}
    if flight and (flight["takeoff_failed"] or flight["land_failed"]):
        failed = {**flight["takeoff_failed"], **flight["land_failed"]}
        return f"take-off or landing failed for {', '.join(sorted(failed))}"
    if result["pose_age_worst_p99_ms"] > POSE_AGE_P99_MS:
        return f"a pose age p99 of {result['pose_age_worst_p99_ms']:.0f} ms"
    total = sum(result["cpu_percent"].values()) + result["sdk_fleet"]["cpu_percent"]
    if total > 100 * MACHINE_BUSY * (os.cpu_count() or 1):
        return f"{total:.0f} % of one core in all, on {os.cpu_count()} cores"
    return ""


def report(results: list[dict[str, object]], title: str) -> None:
    rows = []
    for r in results:
        if "error" in r:
            rows.append([r["drones"], r["error"], *[""] * 12])
            continue
        n, cpu, each = r["drones"], r["cpu_percent"], r["cpu_percent_per_process"]
        flight = r["sdk_fleet"].get("flight") or {}
        flown = "-"
        if flight:
            p99 = flight["pose_age"].get("p99_ms", float("nan"))
            flown = f"{flight['takeoff_ok']}/{flight['land_ok']}, p99 {p99:.0f} ms"
        rows.append([
            n, r["start_s"], each.get("sim", float("nan")), each.get("bridge", float("nan")),
            per_drone(r, "cpu_percent"), cpu["router"], r["sdk_fleet"]["cpu_percent"],
            per_drone(r, "rss_mb"), r["pose_age_p50_ms"], r["pose_age_worst_p99_ms"],
            r.get("pose_rate_hz_min", float("nan")),
            f"{r.get('probed_pose_age_worst_p99_ms', float('nan')):.0f} ms, "
            f"{r.get('probed_pose_rate_hz_min', float('nan')):.0f} Hz",
            f"{r['arming_rtt'].get('p50_ms', 0):.1f}/{r['arming_rtt'].get('p99_ms', 0):.1f}",
            flown,
        ])  # fmt: skip
    print_table(
        title,
        ["N", "start s", "sim %/each", "bridge %/each", "drone %", "router %", "SDK fleet %",
         "MB/drone", "pose age p50", "worst p99", "min Hz", "probed: p99, min Hz",
         "arming p50/p99", "up/down"],
        rows,
    )  # fmt: skip
    print(
        "  (drone % / MB = sim + bridge per drone, without the router; router = the launcher\n"
        "   process holding it; SDK fleet = one Fleet over all N drones, a process of its own;\n"
        "   pose age = arrival at one subscriber - header.stamp, worst drone's p99; min Hz =\n"
        "   the slowest drone's pose rate there; probed = the same while the probes run\n"
        "   (arming calls, the setpoint probe); up/down = drones that\n"
        "   took off / landed through the Fleet, with --fly, and the pose age p99 meanwhile)"
    )


def main(argv: list[str] | None = None) -> int:
    parser = CommandParser(description=first_line(__doc__))
    parser.add_argument("--counts", type=int, nargs="+", default=[1, 5, 10, 20])
    parser.add_argument("--max", type=int, default=60, help="most drones to try for the knee")
    parser.add_argument("--step", type=int, default=10, help="drones added past the counts")
    parser.add_argument("--seconds", type=float, default=10.0, help="measuring window (s)")
    parser.add_argument("--settle", type=float, default=3.0, help="wait after start (s)")
    parser.add_argument("--kind", default="iris", help="iris, tello, or a list (iris,tello)")
    parser.add_argument("--per-process", type=int, default=1, help="drones per process")
    parser.add_argument("--busy", action="store_true", help="keep one core busy meanwhile")
    parser.add_argument("--fly", action="store_true", help="all take off and land, each N")
    parser.add_argument("--fleet-streams", choices=["read", "all"], default="read",
                        help="the SDK fleet's: those it reads, or every getter's")  # fmt: skip
    parser.add_argument("--hold", nargs=5, help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.hold:
        endpoint, count, seconds, fly, streams = args.hold
        hold_fleet(endpoint, int(count), float(seconds), fly == "1", streams)
        return 0

    name = "fleet" if args.kind == "iris" else f"fleet_{args.kind.replace(',', '_')}"
    name += f"_pp{args.per_process}" if args.per_process > 1 else ""
    name += "_busy" if args.busy else ""
    log_dir = REPO / "out" / "bench"
    log_dir.mkdir(parents=True, exist_ok=True)
    results, knee = [], None
    counts = list(args.counts)
    with busy_core(args.busy):
        while counts:
            n = counts.pop(0)
            print(f"... {n} drone(s)", flush=True)
            result = measure(n, args.seconds, args.settle, log_dir, args.kind,
                             args.per_process, args.fly, args.fleet_streams)  # fmt: skip
            result["busy_core"] = args.busy
            results.append(result)
            write_results(name, {"results": results, "partial": True})  # kept if interrupted
            reason = knee_reason(result)
            if reason and knee is None:
                knee = {"drones": n, "reason": reason}
                print(f"    the machine no longer keeps up at {n}: {reason}", flush=True)
            if knee is None and not counts and n + args.step <= args.max:
                counts.append(n + args.step)  # the fixed counts all run; beyond, to the knee
    arrangement = "a process each" if args.per_process == 1 else f"{args.per_process} per process"
    load = "one core kept busy" if args.busy else "no extra load"
    title = (f"A fleet of N simulated drones ({args.kind}, no cameras, {arrangement}, {load}, "
             f"load {os.getloadavg()[0]:.1f}): CPU % of one core, memory, latency ms")  # fmt: skip
    report(results, title)
    ok = [r for r in results if "error" not in r]
    biggest = max(ok, key=lambda r: r["drones"], default=None)
    targets: dict[str, object] = {}
    if args.per_process == 1:
        bridge_share = max((r["cpu_percent_per_process"]["bridge"] for r in ok), default=0)
        targets[f"bridge <= {BRIDGE_SHARE_PER_DRONE:g} % of a core per drone"] = (
            bridge_share <= BRIDGE_SHARE_PER_DRONE
        )
    else:  # a host holds sims and bridges: bench.drone_cost --split measures them apart
        targets["bridge <= 2 % a drone (bench.drone_cost --split)"] = "not measured here"
    targets |= {
        f"{biggest['drones'] if biggest else 0} drones: pose age p99 <= 50 ms": bool(
            biggest and biggest["pose_age_worst_p99_ms"] <= POSE_AGE_P99_MS
        ),
        f"memory <= {MEMORY_PER_DRONE_MB:g} MB per drone": bool(
            biggest and per_drone(biggest, "rss_mb") <= MEMORY_PER_DRONE_MB
        ),
    }
    print_table("targets", ["target", "met"], [[k, v] for k, v in targets.items()])
    last = ok[-1]["drones"] if ok else 0
    print(f"knee: {knee['drones']} drones ({knee['reason']})" if knee else f"knee: above {last}")
    if ok:
        plot(ok, RESULTS / f"{name}.png", title.split(":")[0])
    write_results(name, {"results": results, "knee": knee, "targets": targets})
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
