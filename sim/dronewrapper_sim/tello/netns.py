"""``--netns``: the simulated Tello in a network namespace of its own, joined to the host by a
veth pair, at the real drone's address (192.168.10.1, the host side 192.168.10.2).

The namespace is anonymous: a worker thread of this process ``unshare``s into a new network
namespace and creates the Tello's sockets there (:meth:`TelloNamespace.run_inside`); the rest of
the process (Zenoh) stays in the host's. Nothing names the namespace in ``/var/run/netns``, so
only this process's thread and sockets hold it: when the process exits, even killed with
SIGKILL, the kernel frees the namespace, which destroys the drone end of the veth pair and with
it the host end. The host end is named after the pid (``tsim<pid>h``), removed at a clean exit,
and any whose process is gone is swept at start (belt and braces for a kernel slow to free).
Needs root (CAP_NET_ADMIN) and iproute2's ``ip``.
"""

from __future__ import annotations

import contextlib
import ctypes
import logging
import os
import queue
import re
import subprocess
import threading
from collections.abc import Callable
from typing import Any, TypeVar

from dronewrapper_sim.tello.config import default_netns_subnet, netns_addresses

log = logging.getLogger("sim.tello")

CLONE_NEWNET = 0x40000000
HOST_IF_PATTERN = re.compile(r"^tsim(\d+)h$")
IP_TIMEOUT_S = 10.0

T = TypeVar("T")


def _ip(*args: str) -> str:
    """Run ``ip ARGS`` (in the calling thread's network namespace); its stdout."""
    done = subprocess.run(
        ["ip", *args], capture_output=True, text=True, timeout=IP_TIMEOUT_S, check=False
    )
    if done.returncode != 0:
        raise RuntimeError(f"ip {' '.join(args)}: {done.stderr.strip() or done.returncode}")
    return done.stdout


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


def host_interfaces() -> list[str]:
    """Names of the host ends of simulated Tellos' veth pairs (``tsim<pid>h``)."""
    names = []
    for line in _ip("-o", "link", "show").splitlines():
        parts = line.split(":")
        if len(parts) > 1:
            name = parts[1].strip().split("@")[0]
            if HOST_IF_PATTERN.match(name):
                names.append(name)
    return names


def sweep_stale() -> list[str]:
    """Delete the veth pairs of simulated Tellos whose process is gone; their names."""
    removed = []
    for name in host_interfaces():
        match = HOST_IF_PATTERN.match(name)
        if match and not _alive(int(match.group(1))):
            with contextlib.suppress(RuntimeError):
                _ip("link", "del", name)
                removed.append(name)
    return removed


class _NamespaceThread(threading.Thread):
    """A thread living in a new network namespace, running the calls it is given."""

    def __init__(self) -> None:
        super().__init__(name="tello-netns", daemon=True)
        self.calls: queue.Queue[Any] = queue.Queue()
        self.ready = threading.Event()
        self.error: str | None = None
        self.tid = 0

    def run(self) -> None:
        libc = ctypes.CDLL(None, use_errno=True)
        if libc.unshare(CLONE_NEWNET) != 0:
            self.error = f"unshare(CLONE_NEWNET): {os.strerror(ctypes.get_errno())}"
            self.ready.set()
            return
        self.tid = threading.get_native_id()
        self.ready.set()
        while True:
            item = self.calls.get()
            if item is None:
                return
            fn, box, done = item
            try:
                box.append((True, fn()))
            except BaseException as exc:
                box.append((False, exc))
            done.set()

    def call(self, fn: Callable[[], T]) -> T:
        box: list[tuple[bool, Any]] = []
        done = threading.Event()
        self.calls.put((fn, box, done))
        if not done.wait(IP_TIMEOUT_S * 3):
            raise RuntimeError("the namespace thread did not answer")
        ok, value = box[0]
        if not ok:
            raise value
        return value


class TelloNamespace:
    """The namespace and veth pair of one simulated Tello (see module doc)."""

    def __init__(self, subnet: str) -> None:
        self.drone_address, self.host_address, self.prefix = netns_addresses(subnet)
        pid = os.getpid()
        self.host_if = f"tsim{pid}h"
        self.drone_if = f"tsim{pid}d"
        self._thread = _NamespaceThread()

    @classmethod
    def create(cls, instance: int = 0, subnet: str = "") -> TelloNamespace:
        """Sweep stale pairs, make the namespace and the veth pair, address both ends.

        Raises:
            RuntimeError: a step failed (what was made is removed again).
        """
        swept = sweep_stale()
        if swept:
            log.info("removed stale veth pairs of dead simulated Tellos: %s", ", ".join(swept))
        subnet = subnet or default_netns_subnet(instance)
        in_use = _ip("-o", "-4", "addr", "show", "to", subnet).strip()
        if in_use:
            raise RuntimeError(
                f"{subnet} is already in use on the host ({in_use.split()[1]}: another simulated "
                "Tello?); pick another --instance or tello.netns_subnet"
            )
        ns = cls(subnet)
        try:
            ns._setup()
        except BaseException:
            ns.remove()
            raise
        return ns

    def _setup(self) -> None:
        thread = self._thread
        thread.start()
        thread.ready.wait(IP_TIMEOUT_S)
        if thread.error or not thread.tid:
            raise RuntimeError(thread.error or "the namespace thread did not start")
        _ip("link", "add", self.host_if, "type", "veth", "peer", "name", self.drone_if)
        _ip("link", "set", self.drone_if, "netns", str(thread.tid))
        inside = f"{self.drone_address}/{self.prefix}"
        thread.call(lambda: _ip("link", "set", "lo", "up"))
        thread.call(lambda: _ip("addr", "add", inside, "dev", self.drone_if))
        thread.call(lambda: _ip("link", "set", self.drone_if, "up"))
        _ip("addr", "add", f"{self.host_address}/{self.prefix}", "dev", self.host_if)
        _ip("link", "set", self.host_if, "up")

    def run_inside(self, fn: Callable[[], T]) -> T:
        """``fn()`` run in the namespace (sockets it creates live there)."""
        return self._thread.call(fn)

    def describe(self) -> str:
        return (
            f"drone {self.drone_address} on {self.drone_if}, host {self.host_address}/"
            f"{self.prefix} on {self.host_if}"
        )

    def remove(self) -> None:
        """Delete the veth pair and let the namespace go (idempotent)."""
        if self._thread.is_alive():
            self._thread.calls.put(None)
            self._thread.join(5.0)
        if self.host_if in host_interfaces():
            with contextlib.suppress(RuntimeError):
                _ip("link", "del", self.host_if)
