"""Who is online: liveliness tokens ``{ns}/alive/{service}`` read from the router.

>>> list_drones(connect="tcp/127.0.0.1:7447")     # doctest: +SKIP
['drone1', 'drone2']
"""

from __future__ import annotations

import os

import zenoh

from dronewrapper.errors import NotConnected
from dronewrapper.msgs.registry import ALIVE
from dronewrapper.runtime.node import open_session
from dronewrapper.runtime.options import DEFAULT_ROUTER, ENV_PREFIX, ZenohOptions

BRIDGE_PREFIX = "bridge"
"""A process whose name starts with this is a bridge to an aircraft (bridge_mavlink, bridge)."""


def default_connect() -> str:
    """The router endpoint to use: env ``DRONEWRAPPER_CONNECT`` (first entry) or the default."""
    value = os.environ.get(f"{ENV_PREFIX}CONNECT", "")
    first = next((part.strip() for part in value.split(",") if part.strip()), "")
    return first or DEFAULT_ROUTER


def alive_services(session: zenoh.Session, ns: str = "*", timeout: float = 2.0) -> set[str]:
    """The concrete liveliness keys (``ns/alive/name``) present now, in ``ns`` or all."""
    keys = set()
    for reply in session.liveliness().get(ALIVE.wildcard(ns), timeout=timeout):
        if reply.ok is not None:
            keys.add(str(reply.ok.key_expr))
    return keys


def services_by_namespace(keys: set[str]) -> dict[str, list[str]]:
    """Group liveliness keys into {namespace: sorted service names} (pure)."""
    out: dict[str, list[str]] = {}
    for key in keys:
        parts = ALIVE.match(key)
        if parts is not None:
            out.setdefault(parts["ns"], []).append(parts["service"])
    return {ns: sorted(names) for ns, names in sorted(out.items())}


def open_client(connect: str, timeout: float, *, mode: str = "client") -> zenoh.Session:
    """A session to the router at ``connect`` (``client`` mode unless told otherwise).

    Raises:
        NotConnected: the router cannot be reached within ``timeout`` seconds.
        ValueError: a malformed endpoint or an unknown mode.
    """
    options = ZenohOptions(mode=mode, connect=[connect])
    try:
        return open_session(options, timeout=timeout)
    except ConnectionError as exc:
        raise NotConnected(
            f"cannot reach the Zenoh router at {connect} within {timeout:g} s: is it running? "
            f"(start one with `dronewrapper router --listen {connect}` or "
            "`dronewrapper up compose/sim_iris.yaml`)"
        ) from exc


def list_drones(
    connect: str | None = None,
    *,
    timeout: float = 3.0,
    session: zenoh.Session | None = None,
    bridges_only: bool = True,
) -> list[str]:
    """The namespaces of the drones online, sorted.

    Args:
        connect: router endpoint (default env ``DRONEWRAPPER_CONNECT`` or tcp/127.0.0.1:7447).
        timeout: seconds to reach the router and to collect the answers.
        session: an open Zenoh session to use instead of opening one.
        bridges_only: count a namespace only if a bridge runs in it (a process whose name starts
            with ``bridge``); False lists every namespace with any running process.

    Raises:
        NotConnected: the router cannot be reached.
    """
    own = session is None
    if session is None:
        session = open_client(connect or default_connect(), timeout)
    try:
        grouped = services_by_namespace(alive_services(session, "*", timeout))
    finally:
        if own:
            session.close()
    return [
        ns
        for ns, names in grouped.items()
        if not bridges_only or any(name.startswith(BRIDGE_PREFIX) for name in names)
    ]
