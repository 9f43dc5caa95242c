"""Security benchmark: what TLS + access control and MAVLink 2 signing cost, against plain.

Zenoh: a setpoint (PositionTarget) goes client -> router -> client and a pose comes back, one
at a time, through a router in this process; once over plain ``tcp/`` with no access control,
once over mutual ``tls/`` with the registry's access control on (the router checks every
message). Latency is the round trip (two messages); "added per message" is half the p50
difference. CPU is this process's CPU time (router, both clients, codecs) per round trip.

MAVLink: packing SET_POSITION_TARGET_LOCAL_NED unsigned vs signed, and parsing it with no key
vs verifying the signature (PX4's order, ``verify_signed_frame``), per message; the CPU cost is
given at the bridge's message rates (60 sent/s, 250 received/s).

Targets: <= 0.3 ms added per message p50, <= 5 % CPU.

    python -m bench.security [--round-trips 1000]
"""

from __future__ import annotations

import tempfile
import threading
import time

from pymavlink.dialects.v20 import common as mavlink

from bench.common import percentiles, print_table, write_results
from dronewrapper import setpoints
from dronewrapper.msgs import Header, PoseStamped, PositionTarget, codec, registry
from dronewrapper.router import router_options, run_router
from dronewrapper.runtime.arguments import CommandParser, first_line
from dronewrapper.runtime.node import encoding_for, open_session
from dronewrapper.runtime.options import ZenohOptions
from dronewrapper.security.keystore import KeyStore
from dronewrapper_sim.mavlink_io import VerifyingMAVLink, signing_timestamp

NS = "drone"
BRIDGE_SENT_HZ = 60.0  # setpoints at 30 Hz, heartbeats, commands
BRIDGE_RECEIVED_HZ = 250.0  # telemetry at the bridge's requested rates


def _port() -> int:
    import socket

    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def zenoh_round_trips(endpoint: str, identities: tuple[str, str], keys: str, n: int) -> dict:
    """Ping-pong ``n`` times through the router at ``endpoint``; latency and CPU per trip."""
    ping_id, pong_id = identities
    ping = open_session(ZenohOptions(mode="client", connect=[endpoint], identity=ping_id,
                                     keys_dir=keys))  # fmt: skip
    pong = open_session(ZenohOptions(mode="client", connect=[endpoint], identity=pong_id,
                                     keys_dir=keys))  # fmt: skip
    got = threading.Event()
    pose_pub = pong.declare_publisher(
        registry.LOCAL_POSE.key(NS), encoding=encoding_for(PoseStamped)
    )
    pose = codec.encode(PoseStamped(header=Header.now("map")))
    decode_sp = codec.decoder(PositionTarget)

    def echo(sample) -> None:
        decode_sp.decode(sample.payload.to_bytes())
        pose_pub.put(pose)

    subs = [
        pong.declare_subscriber(registry.SETPOINT_RAW_LOCAL.key(NS), echo),
        ping.declare_subscriber(registry.LOCAL_POSE.key(NS), lambda _s: got.set()),
    ]
    sp_pub = ping.declare_publisher(
        registry.SETPOINT_RAW_LOCAL.key(NS), encoding=encoding_for(PositionTarget)
    )
    target = setpoints.velocity_target(0.0, 0.0, 0.5, 0.0, stamp=time.time())
    rtts: list[float] = []
    try:
        for i in range(n + 50):  # the first 50 warm up (routes, declarations)
            got.clear()
            if i == 50:
                cpu0 = time.process_time()
            t0 = time.perf_counter()
            sp_pub.put(codec.encode(target))
            if not got.wait(2.0):
                raise RuntimeError(f"round trip {i} through {endpoint} got no reply")
            if i >= 50:
                rtts.append(time.perf_counter() - t0)
        cpu_s = time.process_time() - cpu0
    finally:
        for sub in subs:
            sub.undeclare()
        ping.close()
        pong.close()
    return {**percentiles(rtts), "cpu_us_per_round_trip": cpu_s / n * 1e6}


def mavlink_costs(n: int) -> dict:
    """Microseconds per message: pack unsigned/signed, parse plain/verify."""
    key = bytes(range(32))
    msg = mavlink.MAVLink_set_position_target_local_ned_message(
        0, 1, 1, 1, 1991, 0, 0, 0, 0.1, 0.2, -0.5, 0, 0, 0, 0, 0.3
    )
    plain = mavlink.MAVLink(None, srcSystem=255, srcComponent=190)
    signer = mavlink.MAVLink(None, srcSystem=255, srcComponent=190)
    signer.signing.secret_key = key
    signer.signing.sign_outgoing = True
    signer.signing.timestamp = signing_timestamp(time.time())
    out: dict[str, float] = {}
    frames: dict[str, list[bytes]] = {}
    for name, mav in (("unsigned", plain), ("signed", signer)):
        t0 = time.perf_counter()
        frames[name] = [msg.pack(mav, force_mavlink1=False) for _ in range(n)]
        out[f"pack_{name}_us"] = (time.perf_counter() - t0) / n * 1e6
    reader = VerifyingMAVLink(None)
    t0 = time.perf_counter()
    for frame in frames["unsigned"]:
        reader.parse_buffer(frame)
    out["parse_unsigned_us"] = (time.perf_counter() - t0) / n * 1e6
    verifier = VerifyingMAVLink(None)
    verifier.signing.secret_key = key
    verifier.signing.timestamp = signing_timestamp(time.time())
    verifier.signing.allow_unsigned_callback = lambda _m, _i: False
    t0 = time.perf_counter()
    accepted = sum(len(verifier.parse_buffer(frame) or []) for frame in frames["signed"])
    out["parse_verify_us"] = (time.perf_counter() - t0) / n * 1e6
    if accepted != n or verifier.signing.goodsig_count != n:
        raise RuntimeError(f"only {accepted}/{n} signed frames verified")
    return out


def main() -> int:
    parser = CommandParser(description=first_line(__doc__))
    parser.add_argument("--round-trips", type=int, default=1000)
    parser.add_argument("--mavlink-messages", type=int, default=20000)
    args = parser.parse_args()

    keys = tempfile.mkdtemp(prefix="bench_security_")
    store = KeyStore(keys)
    store.init()
    store.issue("drone1", "drone")
    store.issue("alice", "operator")
    plain_ep, tls_ep = f"tcp/127.0.0.1:{_port()}", f"tls/127.0.0.1:{_port()}"
    results: dict[str, dict] = {}
    for mode, listen, identity in (("plain", plain_ep, ""), ("tls_acl", tls_ep, "drone1")):
        stop, ready = threading.Event(), threading.Event()
        options = router_options([listen], identity=identity, keys_dir=keys, acl_namespaces=[NS])
        thread = threading.Thread(target=run_router, args=(options, stop, ready), daemon=True)
        thread.start()
        if not ready.wait(10):
            raise RuntimeError(f"router on {listen} did not start")
        try:
            ids = ("alice", "drone1") if identity else ("", "")
            results[mode] = zenoh_round_trips(listen, ids, keys, args.round_trips)
        finally:
            stop.set()
            thread.join(10)
    plain, tls = results["plain"], results["tls_acl"]
    added_ms = (tls["p50_ms"] - plain["p50_ms"]) / 2
    cpu_added_us = (tls["cpu_us_per_round_trip"] - plain["cpu_us_per_round_trip"]) / 2
    print_table(
        "Zenoh setpoint -> pose round trip through the router (client -> router -> client)",
        ["transport", "n", "p50 ms", "p90 ms", "p99 ms", "CPU µs/trip"],
        [
            [mode, r["n"], r["p50_ms"], r["p90_ms"], r["p99_ms"], r["cpu_us_per_round_trip"]]
            for mode, r in results.items()
        ],
    )
    mav = mavlink_costs(args.mavlink_messages)
    sign_us = mav["pack_signed_us"] - mav["pack_unsigned_us"]
    verify_us = mav["parse_verify_us"] - mav["parse_unsigned_us"]
    mav_cpu_pct = (sign_us * BRIDGE_SENT_HZ + verify_us * BRIDGE_RECEIVED_HZ) / 1e4
    print_table(
        "MAVLink 2 SET_POSITION_TARGET_LOCAL_NED (pymavlink), µs per message",
        ["step", "unsigned", "signed", "added"],
        [
            ["pack (send)", mav["pack_unsigned_us"], mav["pack_signed_us"], sign_us],
            ["parse (receive)", mav["parse_unsigned_us"], mav["parse_verify_us"], verify_us],
        ],
    )
    summary = {
        "tls_acl_added_ms_per_message_p50": added_ms,
        "tls_acl_added_cpu_us_per_message": cpu_added_us,
        "tls_acl_added_cpu_pct_at_300_msgs_per_s": cpu_added_us * 300 / 1e4,
        "signing_added_us_per_message": sign_us + verify_us,
        "signing_added_cpu_pct_at_bridge_rates": mav_cpu_pct,
    }
    print_table("Added by security (targets: <= 0.3 ms/message p50, <= 5 % CPU)",
                ["figure", "value"], [[k, v] for k, v in summary.items()])  # fmt: skip
    write_results("security", {"zenoh": results, "mavlink": mav, "summary": summary})
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
