"""A DroneWrapper's connection: the node it opens when given none, and what is wrong when the drone
cannot be used.

:func:`open_node` opens the wrapper's own :class:`~dronewrapper.runtime.node.Node`: a client of
the router (a ``tls/`` one with an identity), no signal handlers and direct callbacks, since it
lives inside someone else's program. :func:`wait_for_connection` waits, on the node's clock, for
a bridge whose autopilot is connected (the drone client's rule,
:meth:`~dronewrapper.client.DroneClient.connected_state`) and for every stream the getters read.
:func:`diagnose` and :func:`no_reply` turn a silence into one sentence naming what is missing
(no router, no bridge, a bridge without an autopilot, a stream that never came).
"""

from __future__ import annotations

import contextlib
import logging
import os

from dronewrapper import diagnosis
from dronewrapper.client.drone_client import STATE_FRESH_S, DroneClient
from dronewrapper.client.inputs import TELEMETRY_READ_BY_GETTERS
from dronewrapper.diagnosis import identity_facts, seconds
from dronewrapper.discovery import connection_problem
from dronewrapper.errors import DroneError, NotConnected
from dronewrapper.msgs.mavros import State
from dronewrapper.router_reach import why_no_session
from dronewrapper.runtime.node import Node
from dronewrapper.runtime.options import ZenohOptions

log = logging.getLogger("dronewrapper")

SDK_NODE_NAME = "dronewrapper_sdk"
"""The name of a wrapper's own node (its logger, its worker threads)."""


def open_node(ns: str, connect: str, timeout: float, *, mode: str, identity: str) -> Node:
    """The wrapper's own node on the router at ``connect`` (see the module doc).

    Raises:
        NotConnected: no session within ``timeout`` seconds (the message names the cause: no
            router, a refused TLS handshake and by which side, ...).
        ValueError: a malformed endpoint or an unknown mode.
    """
    options = ZenohOptions(mode=mode, connect=[connect], identity=identity, namespace=ns)
    try:
        return Node(
            f"{SDK_NODE_NAME}_{os.getpid()}",  # its liveliness key names this process
            options,
            handle_signals=False,
            open_timeout=timeout,
            direct_callbacks=True,
        )
    except ConnectionError as exc:
        raise NotConnected(why_no_session(connect, timeout, exc)) from exc


def wait_for_connection(client: DroneClient, connect: str, identity: str, timeout: float) -> State:
    """Wait until the bridge reports its autopilot connected and every subscribed stream the
    getters read has arrived; the State.

    Raises:
        NotConnected: no bridge, a bridge without an autopilot, or a stream still missing after
            ``timeout`` s (the message names the missing keys).
    """
    clock, inputs = client.clock, client.inputs
    deadline = clock.monotonic() + timeout
    while (state := client.connected_state()) is None:
        remaining = deadline - clock.monotonic()
        if remaining <= 0:
            raise NotConnected(diagnose(client, connect, identity, timeout))
        with contextlib.suppress(TimeoutError):
            inputs.state.wait(min(remaining, 0.5), newer_than=inputs.state.count)
    awaited = [(what, name) for what, name in TELEMETRY_READ_BY_GETTERS if inputs.subscribed(name)]
    for _, name in awaited:
        with contextlib.suppress(TimeoutError):
            getattr(inputs, name).wait(max(0.0, deadline - clock.monotonic()))
    missing = [
        f"{what} ({getattr(inputs, name).name})"
        for what, name in awaited
        if getattr(inputs, name).value is None
    ]
    if missing:
        raise NotConnected(
            f"the bridge of drone {inputs.ns!r} is connected but after {seconds(timeout)} s "
            f"nothing arrived on: {', '.join(missing)}; is the link too slow, or the bridge "
            "old?"
        )
    log.info("connected to drone %r via %s", inputs.ns, connect)
    return state


def require_connected(client: DroneClient, connect: str, identity: str, what: str) -> State:
    """The connected State, or NotConnected naming ``what`` could not be done and why."""
    state = client.connected_state()
    if state is None:
        raise NotConnected(f"{what}: {diagnose(client, connect, identity, 0.0)}")
    return state


def diagnose(client: DroneClient, connect: str, identity: str, waited: float) -> str:
    """Why the drone is not usable, in one sentence (see discovery.connection_problem)."""
    node, inputs = client.node, client.inputs
    linked = node.linked()
    keys: set[str] = set()
    if linked:
        with contextlib.suppress(Exception):
            keys = node.alive_services("*", timeout=1.0)
    state = inputs.state.value
    return connection_problem(
        inputs.ns,
        connect,
        linked=linked,
        alive_keys=keys,
        state_connected=None if state is None else state.connected,
        state_age=inputs.state.age(),
        fresh_s=STATE_FRESH_S,
        waited=waited,
        **identity_facts(identity, connect),
    )


def no_reply(
    client: DroneClient, connect: str, identity: str, what: str, key: str, timeout: float
) -> DroneError:
    """A call nobody answered, diagnosed (:func:`dronewrapper.diagnosis.no_reply`)."""
    inputs = client.inputs
    try:
        names = client.node.alive_services(inputs.ns, timeout=1.0)
    except Exception:
        names = set()
    return diagnosis.no_reply(
        what,
        key,
        timeout,
        ns=inputs.ns,
        connect=connect,
        alive_names=names,
        sees_telemetry=inputs.state.value is not None,
        **identity_facts(identity, connect),
    )
