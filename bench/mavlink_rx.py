"""What the bridge's MAVLink receive side costs, one step at a time.

A stand-in autopilot (a child process) sends PX4's onboard telemetry as the simulated Iris
does (one datagram per message, at PX4's default rates, ``dronewrapper_sim.px4.telemetry``),
to a receive thread here that reads it for ``--seconds`` with:

1. ``per datagram``: pymavlink's way, as the bridge read before: ``select`` then one
   ``recv_msg`` per message, every message decoded (the untrimmed stream);
2. ``+ drain``: every datagram waiting drained per wake-up, every frame decoded;
3. ``+ id filter``: frames cut by their header, only the ids the bridge reads decoded
   (``dronewrapper_bridge_mavlink.wire``);
4. ``+ trimmed``: the same, with the streams the bridge asks for (``message_rates``) and
   without the ones it stops (``unused_streams``, ATTITUDE while ATTITUDE_QUATERNION flows):
   the bridge as it runs;
5. ``per datagram, trimmed``: step 1 on the trimmed stream: the bridge before the filter;
6. step 4 waking at most every 20 ms (what arrives meanwhile waits for the next wake-up): what
   fewer wake-ups would save, at up to 20 ms more pose age (the bridge does not do it).

It prints the receive thread's CPU (% of one core, ``time.thread_time``), wake-ups, datagrams
and decoded messages per second for each.

    python -m bench.mavlink_rx [--seconds 5]
"""

from __future__ import annotations

import argparse
import os
import socket
import subprocess
import sys
import threading
import time

os.environ.setdefault("MAVLINK20", "1")

from pymavlink.dialects.v20 import common as mavlink

from bench.common import machine, print_table, write_results
from dronewrapper.runtime.arguments import CommandParser, first_line
from dronewrapper_bridge_mavlink.config import DEFAULT_MESSAGE_RATES, UNUSED_STREAMS
from dronewrapper_bridge_mavlink.core import BridgeCore
from dronewrapper_bridge_mavlink.link import MavLink
from dronewrapper_bridge_mavlink.wire import wanted_ids
from dronewrapper_sim.px4.telemetry import ONBOARD_RATES


def sample_messages() -> dict[int, mavlink.MAVLink_message]:
    """One message of every id PX4's onboard link streams, with plausible fields."""
    m = mavlink
    msgs = [
        m.MAVLink_heartbeat_message(2, 12, 0x81, 0, 4, 3),
        m.MAVLink_attitude_message(1000, 0.01, 0.02, 1.5, 0.0, 0.0, 0.0),
        m.MAVLink_attitude_quaternion_message(1000, 1, 0, 0, 0, 0, 0, 0),
        m.MAVLink_global_position_int_message(1000, 473977420, 85455940, 490000, 2000, 1, 2, 3, 90),
        m.MAVLink_local_position_ned_message(1000, 1.0, 2.0, -3.0, 0.1, 0.2, 0.3),
        m.MAVLink_altitude_message(1000, 1, 2, 3, 4, 5, 6),
        m.MAVLink_position_target_local_ned_message(1000, 1, 0, 1, 2, 3, 0, 0, 0, 0, 0, 0, 0, 0),
        m.MAVLink_vfr_hud_message(1.0, 2.0, 90, 50, 3.0, 0.1),
        m.MAVLink_gps_raw_int_message(1000, 3, 473977420, 85455940, 490000, 100, 100, 0, 0, 10),
        m.MAVLink_sys_status_message(0, 0, 0, 100, 12000, 100, 90, 0, 0, 0, 0, 0, 0),
        m.MAVLink_extended_sys_state_message(0, 2),
        m.MAVLink_home_position_message(473977420, 85455940, 490000, 0, 0, 0, [1, 0, 0, 0], 0, 0, 0,
                                        0),
        m.MAVLink_battery_status_message(0, 0, 0, 2500, [4000] * 10, 100, 0, 0, 90),
    ]  # fmt: skip
    return {msg.get_msgId(): msg for msg in msgs}


def trimmed_rates() -> dict[int, float]:
    """PX4's onboard rates after the bridge's SET_MESSAGE_INTERVAL requests."""
    rates = dict(ONBOARD_RATES)
    for name, hz in DEFAULT_MESSAGE_RATES.items():
        rates[getattr(mavlink, f"MAVLINK_MSG_ID_{name}")] = hz
    for name in [*UNUSED_STREAMS, "ATTITUDE"]:
        rates.pop(getattr(mavlink, f"MAVLINK_MSG_ID_{name}"), None)
    return rates


def send(port: int, seconds: float, trimmed: bool) -> None:
    """In the child: stream the messages to 127.0.0.1:port for ``seconds``."""
    mav = mavlink.MAVLink(None, srcSystem=1, srcComponent=1)
    samples = sample_messages()
    rates = trimmed_rates() if trimmed else dict(ONBOARD_RATES)
    frames = {i: bytes(samples[i].pack(mav)) for i in rates}
    sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    start = time.monotonic()
    due = {i: start + k * 0.001 for k, i in enumerate(rates)}
    while (now := time.monotonic()) < start + seconds:
        for i, at in due.items():
            if at <= now:
                sock.sendto(frames[i], ("127.0.0.1", port))
                due[i] = at + 1.0 / rates[i]
        time.sleep(max(0.0, min(due.values()) - time.monotonic()))


def legacy_loop(link: MavLink, until: float, out: dict[str, int]) -> None:
    """The receive loop as it was: a select per datagram, pymavlink's recv_msg per message."""
    conn = link._conn
    while time.monotonic() < until:
        if conn.mav.buf_len() == 0 and not conn.select(0.1):
            continue
        out["wakeups"] += 1
        msg = conn.recv_msg()
        if msg is not None:
            out["decoded"] += 1


def batch_loop(link: MavLink, until: float, out: dict[str, int], period: float = 0.0) -> None:
    """The bridge's loop; with ``period``, at most one wake-up per ``period`` s (what arrives
    meanwhile waits in the socket for the next one)."""
    while (now := time.monotonic()) < until:
        out["decoded"] += len(link.recv_batch(0.1))
        if period:
            time.sleep(max(0.0, now + period - time.monotonic()))


def measure(
    step: str, seconds: float, trimmed: bool, wanted, legacy: bool, period: float = 0.0
) -> dict[str, object]:
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as probe:
        probe.bind(("127.0.0.1", 0))
        port = probe.getsockname()[1]
    link = MavLink(f"udpin:127.0.0.1:{port}", wanted=wanted)
    link.open()
    sender = subprocess.Popen(
        [sys.executable, "-m", "bench.mavlink_rx", "--send", str(port), str(seconds + 1.5),
         "1" if trimmed else "0"]
    )  # fmt: skip
    out = {"wakeups": 0, "decoded": 0}
    cpu: list[float] = []

    def receive() -> None:
        def loop(until: float, into: dict[str, int]) -> None:
            if legacy:
                legacy_loop(link, until, into)
            else:
                batch_loop(link, until, into, period)

        loop(time.monotonic() + 0.5, {"wakeups": 0, "decoded": 0})  # warm-up
        c0, counts0 = time.thread_time(), (link.reading.wakeups, link.reading.reads)
        loop(time.monotonic() + seconds, out)
        cpu.append(time.thread_time() - c0)
        if not legacy:
            out["wakeups"] = link.reading.wakeups - counts0[0]
            out["reads"] = link.reading.reads - counts0[1]

    thread = threading.Thread(target=receive)
    thread.start()
    thread.join()
    sender.wait(10)
    link.close()
    reads = out.get("reads", out["wakeups"])
    return {
        "step": step,
        "cpu_percent": 100 * cpu[0] / seconds,
        "wakeups_per_s": out["wakeups"] / seconds,
        "datagrams_per_s": reads / seconds,
        "decoded_per_s": out["decoded"] / seconds,
        "us_per_datagram": 1e6 * cpu[0] / max(1, reads),
    }


def main(argv: list[str] | None = None) -> int:
    parser = CommandParser(description=first_line(__doc__))
    parser.add_argument("--seconds", type=float, default=5.0)
    parser.add_argument("--send", nargs=3, help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.send:
        send(int(args.send[0]), float(args.send[1]), args.send[2] == "1")
        return 0
    read = wanted_ids(BridgeCore.read_messages(), mavlink)
    steps = [
        ("1 per datagram (before)", False, None, True),
        ("2 + drain per wake-up", False, None, False),
        ("3 + id filter", False, read, False),
        ("4 + trimmed streams (now)", True, read, False),
        ("5 per datagram, trimmed", True, None, True),
        ("6 = 4, a wake-up per 20 ms at most", True, read, False, 0.02),
    ]
    results = [measure(name, args.seconds, *rest) for name, *rest in steps]
    print_table(
        f"MAVLink receive thread, PX4 onboard stream, {args.seconds:g} s each "
        f"(load {os.getloadavg()[0]:.1f})",
        ["step", "CPU % of a core", "wake-ups/s", "datagrams/s", "decoded/s", "µs/datagram"],
        [[r["step"], r["cpu_percent"], r["wakeups_per_s"], r["datagrams_per_s"],
          r["decoded_per_s"], r["us_per_datagram"]] for r in results],
    )  # fmt: skip
    write_results("mavlink_rx", {"machine": machine(), "steps": results})
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
