"""Network namespaces for tests (root only): two hosts joined by a veth pair.

``two_hosts()`` makes a "drone" and a "laptop" namespace, each with loopback up, joined by a
veth pair on a private /24 (10.213.N.0, addresses only inside the namespaces), and removes
both on exit, whatever happened. ``host.argv(...)`` runs a command inside one of them.
"""

from __future__ import annotations

import contextlib
import os
import subprocess
from collections.abc import Iterator
from dataclasses import dataclass


def is_root() -> bool:
    return os.geteuid() == 0


def _ip(*args: str) -> None:
    subprocess.run(["ip", *args], check=True, capture_output=True, timeout=10)


@dataclass(frozen=True)
class Host:
    """One namespace: its name and its address on the veth link."""

    netns: str
    address: str

    def argv(self, *command: str) -> list[str]:
        """``command`` run inside this namespace (``ip netns exec`` execs it: same PID)."""
        return ["ip", "netns", "exec", self.netns, *command]


@contextlib.contextmanager
def two_hosts(tag: str = "") -> Iterator[tuple[Host, Host]]:
    """(drone, laptop) namespaces on one private subnet; removed on exit."""
    suffix = f"{tag}{os.getpid() % 100000}"
    prefix = os.environ.get("DRONEWRAPPER_NETNS_PREFIX", "dw")  # unique per concurrent run
    subnet = f"10.213.{os.getpid() % 250}"
    drone = Host(f"{prefix}d{suffix}", f"{subnet}.1")
    laptop = Host(f"{prefix}l{suffix}", f"{subnet}.2")
    veth = (f"{prefix}vd{suffix}"[:15], f"{prefix}vl{suffix}"[:15])
    made: list[str] = []
    try:
        for host in (drone, laptop):
            _ip("netns", "add", host.netns)
            made.append(host.netns)
            _ip("-n", host.netns, "link", "set", "lo", "up")
        _ip("link", "add", veth[0], "type", "veth", "peer", "name", veth[1])
        for host, dev in zip((drone, laptop), veth, strict=True):
            _ip("link", "set", dev, "netns", host.netns)
            _ip("-n", host.netns, "addr", "add", f"{host.address}/24", "dev", dev)
            _ip("-n", host.netns, "link", "set", dev, "up")
        yield drone, laptop
    finally:
        for netns in made:  # deleting a namespace deletes its end of the veth pair, and the pair
            subprocess.run(["ip", "netns", "del", netns], capture_output=True, timeout=10)
        subprocess.run(["ip", "link", "del", veth[0]], capture_output=True, timeout=10)
