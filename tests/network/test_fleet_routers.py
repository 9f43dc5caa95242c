"""Network tier: a fleet in the field and its operator on the ground, joined by a radio link.

Three network namespaces (root): the field (a router with three simulated Iris and their
bridges, ``compose/sim_fleet.yaml``), the link (a relay that delays every byte 50 ms each way;
both its interfaces shaped to 20 Mbit/s with ``tbf``) and the ground (a router, and an SDK app
with the fleet: ``fleet_ground_probe.py``). The routers speak Zenoh over mTLS with the
project's CA, and the field router enforces the access control generated from the registry:
the ground router connects with an operator's certificate. Every drone's telemetry must reach
the ground fresh (pose age p95 <= 200 ms), a command must reach only its drone, and cutting the
link and restoring it must leave no stale command flying.
"""

from __future__ import annotations

import contextlib
import json
import os
import subprocess
import sys
from collections.abc import Iterator

import pytest

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
PORT = 7448  # inside namespaces of our own: no other test can hold it


class FieldLinkGround:
    """Namespaces ``fl<pid>f`` (field), ``fl<pid>l`` (link) and ``fl<pid>g`` (ground), joined
    field - link - ground by two veth pairs on private subnets that exist only inside them."""

    def __init__(self) -> None:
        base = f"fl{os.getpid()}"
        self.field, self.link, self.ground = f"{base}f", f"{base}l", f"{base}g"
        octet = os.getpid() % 250
        self.field_address, self.link_field_address = f"10.178.{octet}.1", f"10.178.{octet}.2"
        self.link_ground_address, self.ground_address = f"10.179.{octet}.1", f"10.179.{octet}.2"
        self.link_to_field, self.link_to_ground = f"{base}lf", f"{base}lg"
        self._made: list[str] = []

    def up(self) -> None:
        for ns in (self.field, self.link, self.ground):
            _ip("netns", "add", ns)
            self._made.append(ns)
            _ip("-n", ns, "link", "set", "lo", "up")
        for near, far, far_ns, near_address, far_address in (
            (self.link_to_field, f"{self.link_to_field}x", self.field,
             self.link_field_address, self.field_address),
            (self.link_to_ground, f"{self.link_to_ground}x", self.ground,
             self.link_ground_address, self.ground_address),
        ):  # fmt: skip
            _ip("link", "add", near, "netns", self.link, "type", "veth", "peer", "name", far,
                "netns", far_ns)  # fmt: skip
            _ip("-n", self.link, "addr", "add", f"{near_address}/24", "dev", near)
            _ip("-n", far_ns, "addr", "add", f"{far_address}/24", "dev", far)
            _ip("-n", self.link, "link", "set", near, "up")
            _ip("-n", far_ns, "link", "set", far, "up")
            subprocess.run(
                self.argv(self.link, ["tc", "qdisc", "replace", "dev", near, "root", "tbf", "rate",
                                      f"{LINK_MBIT_S}mbit", "burst", "32kb", "latency", "50ms"]),
                check=True, capture_output=True, timeout=10,
            )  # fmt: skip

    def cut(self, down: bool) -> None:
        """Cut (or restore) the link: its interface toward the field goes down (up)."""
        _ip("-n", self.link, "link", "set", self.link_to_field, "down" if down else "up")

    def down(self) -> None:
        for ns in reversed(self._made):  # a namespace takes its ends of the veth pairs along
            _ip("netns", "del", ns, check=False)

    @staticmethod
    def argv(ns: str, argv: list[str]) -> list[str]:
        return ["ip", "netns", "exec", ns, *argv]


def _ip(*args: str, check: bool = True) -> None:
    subprocess.run(["ip", *args], capture_output=True, text=True, check=check, timeout=10)


@contextlib.contextmanager
def field_link_ground() -> Iterator[FieldLinkGround]:
    hosts = FieldLinkGround()
    try:
        hosts.up()
        yield hosts
    finally:
        hosts.down()


def answer(probe: subprocess.Popen) -> None:
    probe.stdin.write("go\n")
    probe.stdin.flush()


@pytest.fixture(scope="module")
def flight(tmp_path_factory) -> dict:
    """The whole scenario, run once: the ground probe's events by name."""
    tmp_path = tmp_path_factory.mktemp("fleet_routers")
    with field_link_ground() as net, contextlib.ExitStack() as stack:
        store = KeyStore(tmp_path / "keys")
        store.init()
        store.issue("field", "drone", hosts=[net.field_address, net.link_ground_address])
        store.issue("ground", "operator")
        keys = str(store.root)
        py = sys.executable
        field = Process(net.argv(net.field, [
            py, "-m", "dronewrapper", "up", "compose/sim_fleet.yaml", "--var", f"drones={DRONES}",
            "--router", "tcp/127.0.0.1:7447", "--listen", f"tls/{net.field_address}:{PORT}",
            "--identity", "field", "--keys", keys,
        ]), tmp_path / "field.log")  # fmt: skip
        stack.callback(field.stop, 60)
        relay = Process(net.argv(net.link, [
            py, "tests/network/delay_relay.py", f"{net.link_ground_address}:{PORT}",
            f"{net.field_address}:{PORT}", str(LINK_DELAY_MS),
        ]), tmp_path / "relay.log")  # fmt: skip
        stack.callback(relay.stop)
        ground = Process(net.argv(net.ground, [
            py, "-m", "dronewrapper", "router", "--listen", "tcp/127.0.0.1:7447",
            "--connect", f"tls/{net.link_ground_address}:{PORT}", "--identity", "ground",
            "--keys", keys,
        ]), tmp_path / "ground.log")  # fmt: skip
        stack.callback(ground.stop)
        wait_for(lambda: "all processes ready" in field.output(), 120, what="the field graph")
        errors = stack.enter_context(open(tmp_path / "probe.err", "w"))
        probe = subprocess.Popen(
            net.argv(net.ground, [py, "tests/network/fleet_ground_probe.py",
                                  "tcp/127.0.0.1:7447", str(DRONES)]),
            cwd=REPO, stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=errors, text=True,
        )  # fmt: skip
        stack.callback(lambda: probe.poll() is None and probe.kill())
        events = {}
        for line in probe.stdout:
            event = json.loads(line)
            events[event["event"]] = event
            if event["event"] == "cut":
                net.cut(True)
                answer(probe)
            elif event["event"] == "restore":
                net.cut(False)
                answer(probe)
            elif event["event"] == "landed":
                break
        assert probe.wait(60) == 0, (tmp_path / "probe.err").read_text()[-3000:]

    print(json.dumps(events, indent=1))
    return events


NAMES = [f"drone{i}" for i in range(1, DRONES + 1)]


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


@pytest.mark.xfail(
    strict=True,
    reason="a bridge judges a setpoint's freshness by its arrival (its stamp is the source "
    "frame's capture time, kept on every repetition): setpoints held in the routers' TCP "
    "stream during a cut arrive in a burst once it is restored and are flown (docs/fleet.md, "
    "'A cut link')",
)
def test_a_command_withdrawn_during_a_cut_never_flies(flight):
    after = flight["after"]
    assert after["max_dx"] < 0.5, after  # the withdrawn command (3 m east) never flew
