"""Network tier: a fleet in the field, its operator on the ground, three routers between them.

Three network namespaces (root), one router each, joined field - link - ground by two veth
pairs on private subnets that exist only inside them:

- field: a router with three simulated Iris and their bridges (``compose/sim_fleet.yaml``),
  which joins the link router (identity ``field``, role ``drone``);
- link: the link router, the relay hop a radio's base station or a cloud relay would be
  (identity ``link``, role ``relay``), listening on both its interfaces; in front of its field
  side, a relay that delays every byte 50 ms each way (``delay_relay.py``: this kernel has no
  ``netem``, so the delay is added in user space), and both its interfaces shaped to 20 Mbit/s
  with ``tbf`` (each direction of the path leaves through one of them);
- ground: a router (identity ``ground``, role ``relay``: it forwards its apps' commands, each
  in the app's name) which joins the link router, and
  an SDK app with the fleet (``fleet_ground_probe.py``).

Every router speaks Zenoh over mTLS with the project's CA and enforces the access control
generated from the registry, from a key folder of its own (``keys export NAME --router``).
The link is measured first (``link_measure.py``, field to ground through the relay and both
shaped interfaces): each way at least 50 ms, and close to it; 20 Mbit/s each way, not more.
Every drone's telemetry must reach the ground fresh (pose age p95 <= 200 ms), a command must
reach only its drone, an observer on the link router must not arm a drone, and cutting the
link and restoring it must leave no stale command flying.
"""

from __future__ import annotations

import contextlib
import json
import os
import re
import signal
import subprocess
import sys
from collections.abc import Iterator

import pytest

from dronewrapper.runtime.children import die_with_parent
from dronewrapper.security.keystore import KeyStore
from support import REPO, Process, wait_for

pytestmark = [
    pytest.mark.network,
    pytest.mark.skipif(os.geteuid() != 0, reason="network namespaces need root (CI runs as root)"),
]

POSE_AGE_P95_S = 0.2
LINK_MBIT_S = 20
LINK_DELAY_MS = 50
DRONES = 3
# inside namespaces of our own: no other test can hold these ports
PORT = 7448  # the link router's TLS listeners
RELAY_PORT = 7449  # the delayed way to the link router, on the link's field side
MEASURE_RELAY_PORT = 7450  # the delayed way to the ground's measurement server
MEASURE_PORT = 7451


class FieldLinkGround:
    """Namespaces ``<prefix><pid>f`` (field), ``…l`` (link) and ``…g`` (ground), joined
    field - link - ground by two veth pairs on private subnets that exist only inside them."""

    def __init__(self) -> None:
        self.prefix = os.environ.get("DRONEWRAPPER_NETNS_PREFIX", "fl")
        base = f"{self.prefix}{os.getpid()}"
        self.field, self.link, self.ground = f"{base}f", f"{base}l", f"{base}g"
        octet = os.getpid() % 250
        self.field_address, self.link_field_address = f"10.178.{octet}.1", f"10.178.{octet}.2"
        self.link_ground_address, self.ground_address = f"10.179.{octet}.1", f"10.179.{octet}.2"
        self.link_to_field, self.link_to_ground = "tofield", "toground"
        self._made: list[str] = []

    def up(self) -> None:
        _sweep_stale(self.prefix)
        for ns in (self.field, self.link, self.ground):
            _ip("netns", "add", ns)
            self._made.append(ns)
            _ip("-n", ns, "link", "set", "lo", "up")
        for near, far_ns, near_address, far_address in (
            (self.link_to_field, self.field, self.link_field_address, self.field_address),
            (self.link_to_ground, self.ground, self.link_ground_address, self.ground_address),
        ):
            far = "tolink"  # each far end is alone in its namespace
            _ip("link", "add", near, "netns", self.link, "type", "veth", "peer", "name", far,
                "netns", far_ns)  # fmt: skip
            _ip("-n", self.link, "addr", "add", f"{near_address}/24", "dev", near)
            _ip("-n", far_ns, "addr", "add", f"{far_address}/24", "dev", far)
            _ip("-n", self.link, "link", "set", near, "up")
            _ip("-n", far_ns, "link", "set", far, "up")
            # what leaves the link toward one end: one direction of the path, at the link's rate
            subprocess.run(
                self.argv(self.link, ["tc", "qdisc", "replace", "dev", near, "root", "tbf", "rate",
                                      f"{LINK_MBIT_S}mbit", "burst", "32kb", "latency", "50ms"]),
                check=True, capture_output=True, timeout=10,
            )  # fmt: skip

    def cut(self, down: bool) -> None:
        """Cut (or restore) the radio: the link's interface toward the field goes down (up)."""
        _ip("-n", self.link, "link", "set", self.link_to_field, "down" if down else "up")

    def down(self) -> None:
        for ns in reversed(self._made):  # a namespace takes its ends of the veth pairs along
            _ip("netns", "del", ns, check=False)

    @staticmethod
    def argv(ns: str, argv: list[str]) -> list[str]:
        return ["ip", "netns", "exec", ns, *argv]


def _ip(*args: str, check: bool = True) -> str:
    done = subprocess.run(["ip", *args], capture_output=True, text=True, check=check, timeout=10)
    return done.stdout


def _sweep_stale(prefix: str) -> None:
    """Remove the namespaces of a run killed before it could (``<prefix><pid>[flg]``, that
    process gone)."""
    for name in _ip("netns", "list", check=False).split():
        made = re.fullmatch(rf"{re.escape(prefix)}(\d+)[flg]", name)
        if made and not os.path.exists(f"/proc/{made.group(1)}"):
            _ip("netns", "del", name, check=False)


@contextlib.contextmanager
def field_link_ground() -> Iterator[FieldLinkGround]:
    hosts = FieldLinkGround()
    try:
        hosts.up()
        yield hosts
    finally:
        hosts.down()


def key_folders(root, net: FieldLinkGround) -> dict[str, str]:
    """One CA; each router's own folder (its certificate and the roles), and an observer's."""
    store = KeyStore(root / "ca")
    store.init()
    store.issue("field", "drone")
    store.issue("link", "relay", hosts=[net.link_field_address, net.link_ground_address])
    store.issue("ground", "relay")
    store.issue("olga", "observer")
    folders = {}
    for name in ("field", "link", "ground", "olga"):
        store.export(name, root / name, router=name != "olga")
        folders[name] = str(root / name)
    return folders


def stop_together(processes: list[Process]) -> None:
    """SIGINT to every process at once, then wait for each (up to 60 s, then SIGKILL)."""
    for process in processes:
        if process.alive():
            process.proc.send_signal(signal.SIGINT)
    for process in processes:
        process.stop(60)


def answer(probe: subprocess.Popen) -> None:
    probe.stdin.write("go\n")
    probe.stdin.flush()


@pytest.fixture(scope="module")
def flight(tmp_path_factory) -> dict:
    """The whole scenario, run once: the link's measurement and the ground probe's events."""
    tmp_path = tmp_path_factory.mktemp("fleet_routers")
    with field_link_ground() as net, contextlib.ExitStack() as stack:
        keys = key_folders(tmp_path, net)
        py = sys.executable
        lf, lg = net.link_field_address, net.link_ground_address

        processes: list[Process] = []
        stack.callback(stop_together, processes)

        def start(ns: str, name: str, argv: list[str]) -> Process:
            processes.append(Process(net.argv(ns, argv), tmp_path / f"{name}.log"))
            return processes[-1]

        measure_server = start(net.ground, "measure_server", [
            py, "tests/network/link_measure.py", "serve", f"{net.ground_address}:{MEASURE_PORT}",
        ])  # fmt: skip
        relay = start(net.link, "relay", [
            py, "tests/network/delay_relay.py", str(LINK_DELAY_MS),
            f"{lf}:{RELAY_PORT}={lf}:{PORT}",
            f"{lf}:{MEASURE_RELAY_PORT}={net.ground_address}:{MEASURE_PORT}",
        ])  # fmt: skip
        start(net.link, "link_router", [
            py, "-m", "dronewrapper", "router", "--listen", f"tls/{lf}:{PORT}",
            "--listen", f"tls/{lg}:{PORT}", "--identity", "link", "--keys", keys["link"],
        ])  # fmt: skip
        start(net.ground, "ground_router", [
            py, "-m", "dronewrapper", "router", "--listen", "tcp/127.0.0.1:7447",
            "--connect", f"tls/{lg}:{PORT}", "--identity", "ground", "--keys", keys["ground"],
        ])  # fmt: skip
        field = start(net.field, "field", [
            py, "-m", "dronewrapper", "up", "compose/sim_fleet.yaml", "--var", f"drones={DRONES}",
            "--router", "tcp/127.0.0.1:7447", "--connect", f"tls/{lf}:{RELAY_PORT}",
            "--identity", "field", "--keys", keys["field"],
        ])  # fmt: skip
        errors = stack.enter_context(open(tmp_path / "probe.err", "w"))
        probe = subprocess.Popen(
            net.argv(net.ground, [py, "tests/network/fleet_ground_probe.py", "tcp/127.0.0.1:7447",
                                  str(DRONES), f"tls/{lg}:{PORT}", keys["olga"]]),
            cwd=REPO, stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=errors, text=True,
            preexec_fn=die_with_parent,
        )  # fmt: skip
        stack.callback(lambda: probe.poll() is None and probe.kill())
        # the link alone, measured while the graph starts and the app connects (both quiet)
        for process in (measure_server, relay):
            wait_for(lambda p=process: "ready" in p.output(), 30, what=process.log_path.name)
        measured = subprocess.run(
            net.argv(net.field, [py, "tests/network/link_measure.py", "measure",
                                 f"{lf}:{MEASURE_RELAY_PORT}"]),
            cwd=REPO, capture_output=True, text=True, timeout=60, preexec_fn=die_with_parent,
        )  # fmt: skip
        assert measured.returncode == 0, measured.stdout + measured.stderr
        events = {"link": json.loads(measured.stdout.splitlines()[-1])}
        wait_for(lambda: "all processes ready" in field.output(), 120, what="the field graph")
        for line in probe.stdout:
            event = json.loads(line)
            events[event["event"]] = event
            if event["event"] == "fleet":
                answer(probe)
            elif event["event"] == "cut":
                net.cut(True)
                answer(probe)
            elif event["event"] == "restore":
                net.cut(False)
                answer(probe)
            elif event["event"] == "landed":
                break
        assert probe.wait(60) == 0, (tmp_path / "probe.err").read_text()[-3000:]

    print(json.dumps(events, indent=1))
    print(summary(events))
    return events


def summary(events: dict) -> str:
    """The figures of one run, in one paragraph."""
    link, ages = events["link"], events["ages"]["ages"]
    lines = [
        f"link: one way {min(link['forward_ms']):.1f}-{max(link['forward_ms']):.1f} ms "
        f"field->ground, {min(link['back_ms']):.1f}-{max(link['back_ms']):.1f} ms back; "
        f"{link['up_mbit_s']:.1f} Mbit/s up, {link['down_mbit_s']:.1f} Mbit/s down (payload)",
        *(f"{ns} pose age at the ground: p50 {a['p50'] * 1000:.1f} ms, "
          f"p95 {a['p95'] * 1000:.1f} ms ({a['n']} poses)" for ns, a in sorted(ages.items())),
        f"after the cut: drone2 moved {events['after']['max_dx']:.2f} m",
    ]  # fmt: skip
    return "\n".join(lines)


NAMES = [f"drone{i}" for i in range(1, DRONES + 1)]


def test_the_link_delays_50_ms_each_way_and_carries_20_mbit_s(flight):
    """Ground truth for the link the fleet flies over: every message takes at least the delay
    each way, the quickest little more; each way carries the shaped rate, never more (at
    least half of it in a 3 MB transfer, whatever TCP's loss recovery costs)."""
    link = flight["link"]
    for way in ("forward_ms", "back_ms"):
        assert min(link[way]) >= LINK_DELAY_MS, (way, link[way])
        assert min(link[way]) <= LINK_DELAY_MS + 15, (way, link[way])
    for way in ("up_mbit_s", "down_mbit_s"):  # TCP's payload: ~95.5 % of the frames' rate
        assert 0.5 * LINK_MBIT_S <= link[way] <= LINK_MBIT_S, (way, link[way])


def test_every_drones_telemetry_reaches_the_ground_fresh(flight):
    assert flight["fleet"]["drones"] == dict.fromkeys(NAMES, "px4")
    ages = flight["ages"]["ages"]
    assert sorted(ages) == NAMES
    for ns, age in ages.items():
        assert age["n"] > 50 and age["p95"] <= POSE_AGE_P95_S, (ns, age)
        assert age["p50"] >= LINK_DELAY_MS / 1000  # the link's delay is really there


def test_a_command_reaches_only_its_drone_and_all_land(flight):
    altitudes = flight["took_off"]["altitudes"]
    assert altitudes["drone2"] > 0.8 and altitudes["drone1"] < 0.2 and altitudes["drone3"] < 0.2
    assert flight["after"]["age"] < 1.0  # telemetry flows again after the cut
    assert flight["landed"]["ok"], flight["landed"]


def test_an_observer_on_the_link_router_watches_but_never_commands(flight):
    observer = flight["observer"]
    assert observer["states"] > 0, observer  # an observer may watch
    assert observer["arm"] == "no_reply" and not observer["drone3_armed"], observer


def test_a_command_withdrawn_during_a_cut_never_flies(flight):
    """The routers' TCP streams hold the setpoints sent during the cut and deliver them in a
    burst; the bridge refuses those that arrive late after their sending (docs/fleet.md)."""
    after = flight["after"]
    assert after["max_dx"] < 0.5, after  # the withdrawn command (3 m east) never flew
