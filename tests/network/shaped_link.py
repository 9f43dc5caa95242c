"""Two test hosts joined by a link of limited bandwidth: Linux network namespaces (root).

``Link`` makes namespaces ``dw<pid><tag>d`` (the drone) and ``dw<pid><tag>l`` (the laptop),
joined by a veth pair with addresses of a small private test subnet that exists only inside
them, and shapes both directions with ``tbf`` (token bucket: rate, burst, queue latency). The
kernel here has no ``netem``, so the link adds no delay of its own. Everything is removed on
exit, and namespaces left by a killed run of this process's parent are swept first.
"""

from __future__ import annotations

import contextlib
import os
import subprocess
from collections.abc import Iterator, Sequence

SUBNET = "192.168.77"
DRONE_ADDRESS = f"{SUBNET}.1"
LAPTOP_ADDRESS = f"{SUBNET}.2"


def is_root() -> bool:
    return os.geteuid() == 0


def _ip(*args: str, check: bool = True) -> subprocess.CompletedProcess:
    return subprocess.run(["ip", *args], capture_output=True, text=True, check=check, timeout=10)


def _sweep_stale(prefix: str = "dw") -> None:
    """Remove test namespaces whose creating process is gone (``dw<pid>…``)."""
    out = _ip("netns", "list", check=False).stdout.split()
    for name in out:
        digits = name[len(prefix) :].rstrip("dl").rstrip("abcdefghijklmnopqrstuvwxyz")
        if name.startswith(prefix) and digits.isdigit() and not os.path.exists(f"/proc/{digits}"):
            _ip("netns", "del", name, check=False)


class Link:
    """The two hosts and the shaped link between them."""

    def __init__(self, tag: str = "a") -> None:
        base = f"dw{os.getpid()}{tag}"
        self.drone, self.laptop = f"{base}d", f"{base}l"
        self._veth_drone, self._veth_laptop = f"{base}vd", f"{base}vl"

    def up(self) -> None:
        _sweep_stale()
        for ns in (self.drone, self.laptop):
            _ip("netns", "add", ns)
            _ip("-n", ns, "link", "set", "lo", "up")
        _ip(
            "link",
            "add",
            self._veth_drone,
            "netns",
            self.drone,
            "type",
            "veth",
            "peer",
            "name",
            self._veth_laptop,
            "netns",
            self.laptop,
        )
        for ns, dev, address in (
            (self.drone, self._veth_drone, DRONE_ADDRESS),
            (self.laptop, self._veth_laptop, LAPTOP_ADDRESS),
        ):
            _ip("-n", ns, "addr", "add", f"{address}/24", "dev", dev)
            _ip("-n", ns, "link", "set", dev, "up")

    def shape(self, mbit_s: float) -> None:
        """Limit both directions to ``mbit_s`` Mbit/s (tbf, 50 ms of queue)."""
        for ns, dev in ((self.drone, self._veth_drone), (self.laptop, self._veth_laptop)):
            subprocess.run(
                [
                    "ip",
                    "netns",
                    "exec",
                    ns,
                    "tc",
                    "qdisc",
                    "replace",
                    "dev",
                    dev,
                    "root",
                    "tbf",
                    "rate",
                    f"{mbit_s}mbit",
                    "burst",
                    "32kb",
                    "latency",
                    "50ms",
                ],
                check=True,
                capture_output=True,
                timeout=10,
            )

    def down(self) -> None:
        for ns in (self.drone, self.laptop):
            _ip("netns", "del", ns, check=False)

    def argv(self, ns: str, argv: Sequence[str]) -> list[str]:
        """``argv`` run inside namespace ``ns``."""
        return ["ip", "netns", "exec", ns, *argv]


@contextlib.contextmanager
def shaped_link(mbit_s: float, tag: str = "a") -> Iterator[Link]:
    link = Link(tag)
    try:
        link.up()
        link.shape(mbit_s)
        yield link
    finally:
        link.down()
