"""bridge_px4_zenoh's CPU under PX4's sample load, replayed from the recording.

A replayer process plays PX4's part on the graph's router (``compose/px4_zenoh.yaml``): it
declares the liveliness tokens recorded from a PX4 SIH (``tests/data/px4_zenoh/sih_ground.json``)
and publishes each recorded sample on its data key, with its rmw attachment, at PX4's rates
(``--rates``, Hz per topic; the default is what PX4 SIH publishes: vehicle_attitude ~230 Hz,
vehicle_local_position and vehicle_global_position ~120 Hz, battery_status ~100 Hz, ...).
An observer counts the bridge's poses. Over ``--seconds`` it reports:

* the bridge process's CPU (user + system time per second of wall time, % of one core);
* the load it ran under (PX4 samples/s actually published);
* the pose rate at the observer (Hz) and the longest gap between two poses (ms).

Run in a network namespace of its own (the graph's router takes tcp/127.0.0.1:7447)::

    unshare -rn sh -c 'ip link set lo up && python -m bench.px4_zenoh_replay_cpu'

Writes bench/results/px4_zenoh_replay_cpu.json.
"""

from __future__ import annotations

import itertools
import json
import multiprocessing
import tempfile
import time
from pathlib import Path

from bench.common import cpu_seconds, print_table, write_results
from dronewrapper.msgs import registry
from dronewrapper.runtime.arguments import CommandParser, first_line
from dronewrapper.runtime.node import Node
from dronewrapper.runtime.options import DEFAULT_ROUTER, ZenohOptions
from dronewrapper_compose.launcher import Launcher

REPO = Path(__file__).resolve().parents[1]
RECORDING = REPO / "tests" / "data" / "px4_zenoh" / "sih_ground.json"
RATES = {
    "vehicle_attitude": 230.0,
    "vehicle_local_position": 120.0,
    "vehicle_global_position": 120.0,
    "vehicle_status": 2.0,
    "battery_status": 100.0,
    "vehicle_land_detected": 1.0,
}


def replay(rates: dict[str, float], seconds: float, counter) -> None:  # type: ignore[no-untyped-def]
    """PX4's part: the recorded tokens, then each recorded sample at its topic's rate."""
    import zenoh

    recording = json.loads(RECORDING.read_text())
    conf = zenoh.Config()
    conf.insert_json5("mode", '"client"')
    conf.insert_json5("connect/endpoints", json.dumps([DEFAULT_ROUTER]))
    session = zenoh.open(conf)
    tokens = [session.liveliness().declare_token(tok) for tok in recording["tokens"]]
    plays = []  # (period s, publisher, payload, attachment)
    for key, sample in recording["samples"].items():
        topic = key.split("/")[-3]
        if rates.get(topic, 0.0) > 0:
            plays.append(
                (
                    1.0 / rates[topic],
                    session.declare_publisher(key),
                    bytes.fromhex(sample["payload"]),
                    bytes.fromhex(sample["attachment"]),
                )
            )
    start = time.monotonic()
    due = [start] * len(plays)
    sent = 0
    while (now := time.monotonic()) < start + seconds:
        for i, (period, publisher, payload, att) in enumerate(plays):
            while due[i] <= now:
                publisher.put(payload, attachment=att)
                due[i] += period
                sent += 1
        counter.value = sent
        time.sleep(0.001)
    for token in tokens:
        token.undeclare()
    session.close()


def measure(seconds: float, rates: dict[str, float], warmup: float, workdir: Path) -> dict:
    log = open(workdir / "graph.log", "w")  # noqa: SIM115 (closed below)
    graph = Launcher.from_file(REPO / "compose" / "px4_zenoh.yaml", namespace="zen", out=log)
    graph.start()
    bridge = graph.children[0].proc.pid
    node = Node(
        "observer",
        ZenohOptions(mode="client", connect=[DEFAULT_ROUTER]),
        handle_signals=False,
        direct_callbacks=True,
    )
    poses: list[float] = []
    node.subscribe(
        registry.LOCAL_POSE,
        lambda _pose: poses.append(time.monotonic()),
        key=registry.LOCAL_POSE.key("zen"),
    )
    spawn = multiprocessing.get_context("spawn")  # not fork: this process has Zenoh threads
    counter = spawn.Value("q", 0)
    player = spawn.Process(target=replay, args=(rates, warmup + seconds + 1.0, counter))
    try:
        player.start()
        time.sleep(warmup)
        cpu0, sent0, since = cpu_seconds(bridge), counter.value, time.monotonic()
        time.sleep(seconds)
        cpu1, sent1, until = cpu_seconds(bridge), counter.value, time.monotonic()
        player.join(timeout=10.0)
    finally:
        if player.is_alive():
            player.terminate()
        node.close()
        graph.stop()
        log.close()
    window = [p for p in poses if since <= p <= until]
    gaps = [b - a for a, b in itertools.pairwise(window)]
    return {
        "seconds": until - since,
        "rates_hz": rates,
        "px4_samples_per_s": (sent1 - sent0) / (until - since),
        "bridge_cpu_percent": 100.0 * (cpu1 - cpu0) / (until - since),
        "pose_rate_hz": len(window) / (until - since),
        "pose_max_gap_ms": 1000.0 * max(gaps, default=float("nan")),
    }


def main(argv: list[str] | None = None) -> int:
    parser = CommandParser(description=first_line(__doc__))
    parser.add_argument("--seconds", type=float, default=20.0, help="measurement window (s)")
    parser.add_argument("--warmup", type=float, default=4.0, help="s replayed before it (s)")
    parser.add_argument("--rates", default=json.dumps(RATES), help="Hz per topic, JSON")
    parser.add_argument("--label", default="", help="a name for this run in the results")
    args = parser.parse_args(argv)
    with tempfile.TemporaryDirectory() as tmp:
        result = measure(args.seconds, json.loads(args.rates), args.warmup, Path(tmp))
    result["label"] = args.label
    print_table(
        "bridge_px4_zenoh under PX4's replayed load",
        ["label", "px4 samples/s", "bridge CPU %", "pose Hz", "pose max gap ms"],
        [
            [
                args.label,
                f"{result['px4_samples_per_s']:.0f}",
                f"{result['bridge_cpu_percent']:.1f}",
                f"{result['pose_rate_hz']:.1f}",
                f"{result['pose_max_gap_ms']:.0f}",
            ]
        ],
    )
    write_results("px4_zenoh_replay_cpu", result)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
