"""``dronewrapper doctor``: diagnose a setup and say what to fix.

Checks, in order: the router is reachable; which processes are alive in which namespace; each
drone's autopilot link (kind, connected, mode, battery) and how full it is (``link 94 %
full``, from the bridge's link status); ROS 2 (rmw_zenoh) endpoints that
disagree on a type or its hash; every telemetry stream's rate and age
against the registry; the senders' clocks against this computer's; the link bandwidth through
the router. Each line starts with ``ok``, ``warn`` or ``FAIL``; the exit status is 1 if any check
failed. Images are left out unless asked for (``--images``): on a slow link, listening to raw
frames would be the problem it diagnoses.
"""

from __future__ import annotations

import secrets
import threading
import time
from collections import defaultdict
from collections.abc import Callable, Iterable
from dataclasses import dataclass

import msgspec
import zenoh

from dronewrapper.discovery import alive_services, services_by_namespace
from dronewrapper.health import (
    FAIL,
    OK,
    WARN,
    StreamHealth,
    StreamLog,
    bandwidth_advice,
    clock_advice,
    describe_stream,
    judge_stream,
)
from dronewrapper.msgs import codec
from dronewrapper.msgs.link import LinkStatus
from dronewrapper.msgs.mavros import State
from dronewrapper.msgs.registry import LINK_STATUS, STATE, TOPICS, Topic, topic_for_key
from dronewrapper.msgs.sensor import BatteryState, CompressedImage, Image
from dronewrapper.router_reach import NO_ROUTER_HINT, open_client_session
from dronewrapper.runtime.node import open_session
from dronewrapper.runtime.options import ZenohOptions

Report = Callable[[str, str], None]
"""Called with (verdict, sentence) for each finding."""

PROBE_CHUNK = 256 * 1024
PROBE_BYTES = 16 * 1024 * 1024


@dataclass
class Heard:
    """Everything heard while listening, by key."""

    logs: dict[str, StreamLog]
    topics: dict[str, Topic]
    latest: dict[str, object]
    end: float


def topic_families(images: bool) -> list[str]:
    """Key expressions covering every registered topic (with or without the image ones)."""
    heavy = (Image, CompressedImage)
    return sorted({t.wildcard() for t in TOPICS.values() if images or t.type not in heavy})


def listen(session: zenoh.Session, families: Iterable[str], seconds: float) -> Heard:
    """Subscribe to ``families`` for ``seconds`` and log arrivals, stamp skews and sizes."""
    logs: dict[str, StreamLog] = defaultdict(StreamLog)
    topics: dict[str, Topic] = {}
    latest: dict[str, object] = {}
    lock = threading.Lock()

    def on_sample(sample: zenoh.Sample) -> None:
        arrival, wall = time.monotonic(), time.time()
        key = str(sample.key_expr)
        payload = sample.payload.to_bytes()
        topic = topic_for_key(key)
        skew, msg = None, None
        if topic is not None:
            try:
                msg = codec.decode(topic.type, payload)
            except (msgspec.DecodeError, msgspec.ValidationError):
                msg = None
            header = getattr(msg, "header", None)
            if header is not None and header.stamp > 0:
                skew = wall - float(header.stamp)
        with lock:
            logs[key].add(arrival, skew, len(payload))
            if topic is not None:
                topics[key] = topic
            if msg is not None:
                latest[key] = msg

    subs = [session.declare_subscriber(family, on_sample) for family in families]
    try:
        time.sleep(seconds)
    finally:
        for sub in subs:
            sub.undeclare()
    with lock:
        return Heard(dict(logs), dict(topics), dict(latest), time.monotonic())


def measure_bandwidth(options: ZenohOptions, session: zenoh.Session, timeout: float) -> float:
    """Mbit/s of a burst sent by ``session`` and received by a second session, both through
    the router (so the link is crossed twice when the router is on another machine); 0 when
    the burst did not come back within ``timeout``."""
    key = f"doctor/{secrets.token_hex(4)}/probe"
    received = 0
    done = threading.Event()
    first: list[float] = []

    def on_probe(sample: zenoh.Sample) -> None:
        nonlocal received
        if not first:
            first.append(time.monotonic())
        received += len(sample.payload)
        if received >= PROBE_BYTES:
            done.set()

    receiver = open_session(ZenohOptions(mode="client", connect=options.connect), timeout=timeout)
    try:
        sub = receiver.declare_subscriber(key, on_probe)
        time.sleep(0.3)  # the router learns the subscription before the burst
        pub = session.declare_publisher(
            key, congestion_control=zenoh.CongestionControl.BLOCK, express=False
        )
        chunk = bytes(PROBE_CHUNK)
        start = time.monotonic()
        for _ in range(PROBE_BYTES // PROBE_CHUNK):
            pub.put(chunk)
        ok = done.wait(timeout)
        elapsed = time.monotonic() - start
        pub.undeclare()
        sub.undeclare()
    finally:
        receiver.close()
    return received * 8 / 1e6 / elapsed if ok and elapsed > 0 else 0.0


def describe_drone(ns: str, processes: list[str], latest: dict[str, object]) -> tuple[str, str]:
    """(verdict, sentence) about one namespace: its processes and its autopilot link (pure)."""
    state = latest.get(STATE.key(ns))
    names = ", ".join(processes)
    if not isinstance(state, State):
        bridges = [p for p in processes if p.startswith("bridge")]
        if bridges:
            return FAIL, f"drone {ns!r}: {names} alive, but no State heard from its bridge"
        return OK, f"namespace {ns!r}: {names} alive (no aircraft bridge)"
    battery = latest.get(f"{ns}/mavros/battery")
    charge = (
        f", battery {battery.percentage * 100:.0f} %"
        if isinstance(battery, BatteryState) and battery.percentage == battery.percentage
        else ""
    )
    link = "connected" if state.connected else "NOT connected to its autopilot"
    armed = "armed" if state.armed else "disarmed"
    sentence = (
        f"drone {ns!r} ({state.autopilot or 'unknown autopilot'}): {link}, mode {state.mode}, "
        f"{armed}{charge}; alive: {names}"
    )
    return (OK if state.connected else FAIL), sentence


LINK_WARN_LOAD = 0.8
"""A serial autopilot link this full is reported (the bridge's own warning threshold)."""


def describe_link(ns: str, latest: dict[str, object]) -> tuple[str, str] | None:
    """(verdict, sentence) about drone ``ns``'s autopilot link, or None when its bridge does
    not report one (pure): ``warn`` from :data:`LINK_WARN_LOAD` full, ``FAIL`` when full."""
    status = latest.get(LINK_STATUS.key(ns))
    if not isinstance(status, LinkStatus):
        return None
    sentence = f"drone {ns!r}: {status.describe()}"
    if status.load >= 1.0:
        return FAIL, f"{sentence}; telemetry is being lost: lower message_rates or raise the baud"
    if status.load >= LINK_WARN_LOAD:
        return WARN, f"{sentence}; near its limit: lower message_rates or raise the baud"
    return OK, sentence


def bridge_streams(ns: str) -> list[str]:
    """The keys of every periodic stream a bridge publishes for drone ``ns`` (registry)."""
    return [
        topic.key(ns)
        for topic in TOPICS.values()
        if "bridge" in topic.publishers and topic.rate_hz > 0 and topic.fields == ("ns",)
    ]


def stream_findings(heard: Heard) -> list[StreamHealth]:
    """Every heard stream, and every bridge stream of the drones heard, judged (pure)."""
    namespaces = {match["ns"] for key in heard.logs if (match := STATE.match(key)) is not None}
    keys = set(heard.logs).union(*(bridge_streams(ns) for ns in namespaces))
    findings = []
    for key in sorted(keys):
        if key.endswith("global_position/global") and key not in heard.logs:
            continue  # no GPS is a fact, not a fault (a Tello, an indoor flight)
        if LINK_STATUS.match(key) and key not in heard.logs:
            continue  # only bridge_mavlink reports its link
        topic = heard.topics.get(key) or topic_for_key(key)
        expected = topic.rate_hz if topic is not None else 0.0
        findings.append(judge_stream(key, expected, heard.logs.get(key, StreamLog()), heard.end))
    return findings


def ros2_findings(session: zenoh.Session, timeout: float = 1.0) -> list[tuple[str, str]]:
    """ROS 2 endpoints (rmw_zenoh liveliness tokens) on this router: each topic or service
    whose endpoints disagree on its type or hash is a FAIL naming both sides (they never
    exchange a message); none at all, no finding. The ROS 2 codec ships with the on-board
    stack, not with the SDK: without it, no finding either."""
    try:
        from dronewrapper_ros2_codec.mismatch import disagreements
        from dronewrapper_ros2_codec.names import ADMIN, parse_endpoint
    except ImportError:  # a laptop's SDK alone (pip install ./sdk)
        return []

    endpoints = []
    for reply in session.liveliness().get(f"{ADMIN}/**", timeout=timeout):
        if reply.ok is not None and (found := parse_endpoint(str(reply.ok.key_expr))):
            endpoints.append(found)
    if not endpoints:
        return []
    problems = disagreements(endpoints)
    if problems:
        return [(FAIL, problem.describe()) for problem in problems]
    names = {e.topic for e in endpoints}
    return [(OK, f"ROS 2: {len(endpoints)} endpoints on {len(names)} names, all types agree")]


def run_doctor(
    options: ZenohOptions,
    report: Report,
    *,
    listen_s: float = 3.0,
    images: bool = False,
    bandwidth: bool = True,
    timeout: float = 5.0,
) -> int:
    """Run every check, reporting each finding; returns 1 if one failed, else 0."""
    failed = False

    def say(verdict: str, text: str) -> None:
        nonlocal failed
        failed |= verdict == FAIL
        report(verdict, text)

    where = ", ".join(options.connect) or "the default router"
    started = time.monotonic()
    try:
        session = open_client_session(options, timeout=timeout)
    except ConnectionError as exc:
        hint = "" if NO_ROUTER_HINT in str(exc) else f"; {NO_ROUTER_HINT}"
        say(FAIL, f"router: {exc}{hint}")
        return 1
    try:
        say(OK, f"router {where} reachable ({(time.monotonic() - started) * 1000:.0f} ms)")
        grouped = services_by_namespace(alive_services(session, "*", timeout=timeout))
        if not grouped:
            say(FAIL, "no DroneWrapper process is alive on this router: is the graph running?")
        heard = listen(session, topic_families(images), listen_s)
        for ns, processes in grouped.items():
            say(*describe_drone(ns, processes, heard.latest))
            if (link := describe_link(ns, heard.latest)) is not None:
                say(*link)
        for finding in ros2_findings(session, min(timeout, 1.0)):
            say(*finding)
        for health in stream_findings(heard):
            if health.verdict != OK or health.expected_hz > 0:
                say(health.verdict, describe_stream(health))
        skews = [s for log in heard.logs.values() for s in log.skews]
        say(*clock_advice(skews))
        if bandwidth:
            say(*bandwidth_advice(measure_bandwidth(options, session, timeout)))
    finally:
        session.close()
    return 1 if failed else 0


__all__ = ["FAIL", "OK", "WARN", "run_doctor"]
