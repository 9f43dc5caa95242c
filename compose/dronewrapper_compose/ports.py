"""A graph's own ports: taken ones are refused with a clear message, ``auto`` picks a free one.

Two graphs using the same UDP port cross-talk silently: the bridge's listening socket allows
address reuse, so a second simulator's datagrams reach the first graph's bridge, which then sees
two autopilots. A graph names the variables that are ports it binds on this machine
(``ports: {onboard_port: udp}``); before anything starts the launcher checks each is free, and
a value of ``auto`` (the simulated graphs' default) is replaced by a free port.
"""

from __future__ import annotations

import errno
import random
import socket
from collections.abc import Mapping
from pathlib import Path

PORT_KINDS = {"udp": socket.SOCK_DGRAM, "tcp": socket.SOCK_STREAM}
AUTO = "auto"


class PortInUse(ValueError):
    """A port a graph needs is already bound; the message names the variable and the port."""


def port_in_use(kind: str, port: int, host: str = "127.0.0.1") -> bool:
    """Whether ``port`` (``kind`` udp/tcp) on ``host`` is bound by someone.

    UDP: a test bind without address reuse, which fails even against sockets that allow reuse
    (the bridge's). TCP: a test bind with address reuse, as the router binds: it fails against
    a bound or listening socket but not against connections left in TIME_WAIT by a stopped
    graph (those hold the port for a minute, and the router binds over them).
    """
    with socket.socket(socket.AF_INET, PORT_KINDS[kind]) as sock:
        if kind == "tcp":
            sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        try:
            sock.bind((host, port))
        except OSError as exc:
            if exc.errno in (errno.EADDRINUSE, errno.EACCES):
                return True
            raise
    return False


def free_port(kind: str | int = "tcp", host: str = "127.0.0.1") -> int:
    """A port of ``kind`` that is free on ``host`` right now: the project's one copy (graphs,
    tests, benchmarks). ``kind`` is ``"tcp"``/``"udp"`` or ``socket.SOCK_STREAM``/``SOCK_DGRAM``.
    """
    socktype = PORT_KINDS[kind] if isinstance(kind, str) else kind
    with socket.socket(socket.AF_INET, socktype) as sock:
        sock.bind((host, 0))
        return sock.getsockname()[1]


EPHEMERAL_RANGE_FILE = Path("/proc/sys/net/ipv4/ip_local_port_range")
FIXED_PORTS_FROM = 10000
"""The lowest port :func:`free_fixed_port` picks."""


def ephemeral_range() -> tuple[int, int]:
    """The ports this machine hands out to sockets bound to port 0 (Linux's
    ``ip_local_port_range``; IANA's 49152-65535 where it cannot be read)."""
    try:
        low, high = (int(v) for v in EPHEMERAL_RANGE_FILE.read_text().split())
    except (OSError, ValueError):
        return 49152, 65535
    return low, high


def free_fixed_port(kind: str = "udp", host: str = "127.0.0.1", tries: int = 200) -> int:
    """A port of ``kind`` free on ``host`` now and outside the ephemeral range, so that no
    socket bound to port 0 meanwhile (a simulator's link, any other program's) can take it
    before its owner binds it: a fleet's bridge ports, chosen before N simulators start and
    bind their own links to port 0. Falls back to :func:`free_port` when none is found.
    """
    low, _high = ephemeral_range()
    if low - 1 > FIXED_PORTS_FROM:
        for _ in range(tries):
            port = random.randint(FIXED_PORTS_FROM, low - 1)
            if not port_in_use(kind, port, host):
                return port
    return free_port(kind, host)


def private_links() -> dict[str, str]:
    """A simulated graph's autopilot links on free UDP ports (the ``onboard_port`` and
    ``gcs_port`` variables), so that graphs side by side, or a ground station on 14550,
    never hear each other's autopilot."""
    return {
        "onboard_port": str(free_port(socket.SOCK_DGRAM)),
        "gcs_port": str(free_port(socket.SOCK_DGRAM)),
    }


def choose_ports(ports: Mapping[str, str], values: Mapping[str, str]) -> dict[str, str]:
    """The port variables with ``auto`` replaced by free ports (others as given).

    Raises:
        ValueError: a port variable is missing, not ``auto`` and not a port number, or of an
            unknown kind.
    """
    chosen = {}
    for var, kind in ports.items():
        if kind not in PORT_KINDS:
            raise ValueError(f"ports.{var}: kind must be udp or tcp, got {kind!r}")
        value = values.get(var)
        if value is None:
            raise ValueError(f"ports.{var}: no variable ${{{var}}} to hold the port")
        if value == AUTO:
            chosen[var] = str(free_port(kind))
            continue
        if not (value.isdigit() and 1 <= int(value) <= 65535):
            raise ValueError(f"{var}={value!r} must be a port number 1-65535 or {AUTO}")
        chosen[var] = value
    return chosen


def check_ports_free(ports: Mapping[str, str], values: Mapping[str, str]) -> None:
    """Refuse if a graph's port is already bound.

    Raises:
        PortInUse: names the variable, the port and what to do.
    """
    for var, kind in ports.items():
        port = int(values[var])
        if port_in_use(kind, port):
            raise PortInUse(
                f"{kind.upper()} port {port} (${{{var}}}) is already in use on this machine "
                f"(another graph or autopilot link?); stop it, or pick another port with "
                f"--var {var}=N (or --var {var}={AUTO})"
            )


def router_port_in_use(endpoint: str) -> int | None:
    """The TCP port of a ``tcp/HOST:PORT`` router endpoint when it is already bound, else None."""
    proto, _, rest = endpoint.partition("/")
    host, _, port = rest.rpartition(":")
    if proto != "tcp" or not port.isdigit():
        return None
    host = host.strip("[]")
    if host not in ("127.0.0.1", "localhost", "0.0.0.0"):
        return None
    return int(port) if port_in_use("tcp", int(port), "127.0.0.1") else None
