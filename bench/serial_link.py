"""Serial-link benchmark: the simulator's autopilot behind a serial line at each baud.

For each case the simulator, a paced pseudo-terminal (``dronewrapper_sim.serial_relay``) and
the bridge on that device run on a loopback router with the aircraft on the ground; after
``--settle`` s (the stream requests have taken effect) it measures for ``--seconds`` s: the
line's load and bytes/s as the bridge reports them (``{ns}/bridge/link``), the pose rate on
Zenoh, the frames the line dropped, and each frame's time on the line from the autopilot to
the bridge (waiting behind the frames before it, then its own bytes). Cases: 57600, 115200 and
921600 baud with the bridge's budget (``link_share`` 0.6), 57600 with the configured rates
(``link_share`` 1.0) and 57600 signed.

    python -m bench.serial_link [--seconds 10] [--settle 10]
"""

from __future__ import annotations

import subprocess
import sys
import tempfile
import time

from bench.common import percentiles, print_table, started_router, stop_process, write_results
from dronewrapper.msgs import registry
from dronewrapper.runtime.arguments import CommandParser, first_line
from dronewrapper.runtime.node import Node
from dronewrapper.runtime.options import ZenohOptions
from dronewrapper.security.keystore import KeyStore
from dronewrapper_compose.ports import free_port
from dronewrapper_sim.serial_relay import SerialRelay

CASES = [  # (baud, link_share, signed)
    (57600, 0.6, False),
    (57600, 1.0, False),
    (57600, 0.6, True),
    (115200, 0.6, False),
    (921600, 0.6, False),
]


def measure(router: str, baud: int, share: float, key: str, settle: float, seconds: float) -> dict:
    """One case: start the three, wait ``settle`` s, measure ``seconds`` s."""
    port = free_port("udp")
    with SerialRelay(baud, udp_listen=("127.0.0.1", port)) as relay:
        signing = ["--set", f"signing_key_file={key}"] if key else []
        bridge = subprocess.Popen(
            [sys.executable, "-m", "dronewrapper_bridge_mavlink", "--connect", router,
             "--connection", relay.path, "--baud", str(baud), "--set", f"link_share={share}",
             *signing],
            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
        )  # fmt: skip
        sim = subprocess.Popen(
            [sys.executable, "-m", "dronewrapper_sim", "--scenario", "empty", "--no-cameras",
             "--udp-onboard", f"{port}:0", "--udp-gcs", "off", "--connect", router,
             *(["--signing-key", key] if key else [])],
            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
        )  # fmt: skip
        links: list = []
        poses: list[float] = []
        options = ZenohOptions(mode="client", connect=[router], name="bench")
        try:
            with Node("bench", options, handle_signals=False) as node:
                node.subscribe(registry.LINK_STATUS, links.append)
                node.subscribe(registry.LOCAL_POSE, lambda _m: poses.append(time.monotonic()))
                time.sleep(settle)
                dropped, start, count = relay.down.dropped_frames, time.monotonic(), len(poses)
                relay.down.delays.clear()
                time.sleep(seconds)
                elapsed = time.monotonic() - start
                pose_hz = (len(poses) - count) / elapsed
                dropped = relay.down.dropped_frames - dropped
                delays = list(relay.down.delays)
        finally:
            stop_process(sim)
            stop_process(bridge)
    if not links or not delays:
        return {"baud": baud, "share": share, "signed": bool(key), "error": "no link status"}
    link = links[-1]
    return {
        "baud": baud,
        "share": share,
        "signed": bool(key),
        "stream_scale": link.stream_scale,
        "load": link.load,
        "down_Bps": link.received_rate,
        "pose_hz": pose_hz,
        "dropped_per_s": dropped / elapsed,
        "line_ms": percentiles(delays),
    }


def main() -> int:
    parser = CommandParser(description=first_line(__doc__))
    parser.add_argument("--seconds", type=float, default=10.0)
    parser.add_argument("--settle", type=float, default=10.0)
    args = parser.parse_args()
    router = started_router()
    results = []
    with tempfile.TemporaryDirectory() as keys:
        store = KeyStore(keys)
        store.new_mavlink_key()
        try:
            for baud, share, signed in CASES:
                key = str(store.mavlink_key) if signed else ""
                results.append(measure(router.endpoint, baud, share, key, args.settle,
                                       args.seconds))  # fmt: skip
        finally:
            router.stop()
    rows = [
        [r["baud"], r["share"], "yes" if r["signed"] else "no",
         f"{r['stream_scale'] * 100:.0f} %", f"{r['load'] * 100:.0f} %",
         f"{r['down_Bps'] / 1000:.1f}", f"{r['pose_hz']:.0f}", f"{r['dropped_per_s']:.1f}",
         f"{r['line_ms']['p50_ms']:.0f} / {r['line_ms']['p90_ms']:.0f}"]
        for r in results if "error" not in r
    ]  # fmt: skip
    print_table(
        "serial line, aircraft on the ground (after the stream requests)",
        ["baud", "share", "signed", "streams", "load", "down kB/s", "pose Hz", "drops/s",
         "line ms p50 / p90"],
        rows,
    )  # fmt: skip
    write_results("serial_link", {"cases": results})
    return 0 if len(rows) == len(CASES) else 1


if __name__ == "__main__":
    raise SystemExit(main())
