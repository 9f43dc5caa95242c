"""Who is online: liveliness tokens ``{ns}/alive/{service}`` read from the router.

>>> list_drones(connect="tcp/127.0.0.1:7447")     # doctest: +SKIP
['drone1', 'drone2']
"""

from __future__ import annotations

import os

import zenoh

from dronewrapper.diagnosis import refused_identity, seconds
from dronewrapper.errors import NotConnected
from dronewrapper.msgs.registry import ALIVE, STATE
from dronewrapper.runtime.node import alive_services, open_session
from dronewrapper.runtime.options import (
    DEFAULT_ROUTER,
    ENV_PREFIX,
    ZenohOptions,
)

BRIDGE_PREFIX = "bridge"
"""A process whose name starts with this is a bridge to an aircraft (bridge_mavlink, bridge)."""


def default_connect() -> str:
    """The router endpoint to use: env ``DRONEWRAPPER_CONNECT`` (first entry) or the default."""
    value = os.environ.get(f"{ENV_PREFIX}CONNECT", "")
    first = next((part.strip() for part in value.split(",") if part.strip()), "")
    return first or DEFAULT_ROUTER


def services_by_namespace(keys: set[str]) -> dict[str, list[str]]:
    """Group liveliness keys into {namespace: sorted service names} (pure)."""
    out: dict[str, list[str]] = {}
    for key in keys:
        parts = ALIVE.match(key)
        if parts is not None:
            out.setdefault(parts["ns"], []).append(parts["service"])
    return {ns: sorted(names) for ns, names in sorted(out.items())}


def connection_problem(
    ns: str,
    connect: str,
    *,
    linked: bool,
    alive_keys: set[str],
    state_connected: bool | None,
    state_age: float,
    fresh_s: float,
    waited: float,
    identity: str = "",
    standing: tuple[str, bool] | None = None,
) -> str:
    """Why a drone is not usable, in one sentence naming what is missing (pure).

    Args:
        ns: the drone's namespace; connect: the router endpoint.
        linked: the session has a router or a peer.
        alive_keys: liveliness keys seen (``ns/alive/name``).
        state_connected: ``State.connected`` of the newest State, None if none arrived.
        state_age: seconds since the newest State; fresh_s: older is "stopped".
        waited: seconds waited, for the message.
        identity: our certificate on a ``tls/`` router ("" on a plain link); with it, a router
            that shows nothing at all, or a local key store that says revoked, means the
            router refused the identity.
        standing: ``(role, refused)`` from the local key store, None when unknown.
    """
    state_key = STATE.key(ns)
    if not linked:
        return f"cannot reach the Zenoh router at {connect}: no router or peer linked"
    revoked = standing is not None and standing[1]
    if identity and state_connected is None and (revoked or not alive_keys):
        return refused_identity(identity, connect)
    grouped = services_by_namespace(alive_keys)
    here = grouped.get(ns, [])
    elsewhere = [
        other
        for other, names in grouped.items()
        if other != ns and any(name.startswith(BRIDGE_PREFIX) for name in names)
    ]
    alive = ", ".join(here) or "nothing"
    hint = f"; drones online: {', '.join(elsewhere)}" if elsewhere else ""
    if state_connected is None:
        bridges = [name for name in here if name.startswith(BRIDGE_PREFIX)]
        if bridges:
            return (
                f"bridge {', '.join(bridges)} is alive in namespace {ns!r} but published no "
                f"State on {state_key} within {seconds(waited)} s"
            )
        return (
            f"no bridge for drone {ns!r} on the router at {connect}: nothing published "
            f"{state_key} within {seconds(waited)} s (alive in {ns!r}: {alive}{hint}). Start one, "
            "e.g. `dronewrapper up compose/sim_iris.yaml`"
        )
    if state_age > fresh_s:
        return (
            f"the bridge of drone {ns!r} stopped publishing {state_key} {state_age:.1f} s ago "
            f"(alive in {ns!r}: {alive})"
        )
    if not state_connected:
        return (
            f"the bridge of drone {ns!r} is up but its autopilot is not connected (no "
            f"heartbeat) after {seconds(waited)} s"
        )
    return f"drone {ns!r} is connected"


def open_client(
    connect: str, timeout: float, *, mode: str = "client", identity: str = ""
) -> zenoh.Session:
    """A session to the router at ``connect`` (``client`` mode unless told otherwise);
    ``identity`` is the certificate for a ``tls/`` router (see ``dronewrapper keys``).

    Raises:
        NotConnected: the router cannot be reached within ``timeout`` seconds.
        ValueError: a malformed endpoint or an unknown mode.
    """
    options = ZenohOptions(mode=mode, connect=[connect], identity=identity)
    try:
        return open_session(options, timeout=timeout)
    except ConnectionError as exc:
        from dronewrapper.router_reach import why_no_session

        raise NotConnected(why_no_session(connect, timeout, exc)) from exc


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
