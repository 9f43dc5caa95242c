"""A Zenoh router as a Python process (no extra binary): ``dronewrapper router``.

Secure by default wherever the link leaves the machine: a plain ``tcp/`` (or ``udp/``)
listener on an address other than loopback is refused unless ``insecure`` is set, because
anyone on that network could then fly the drone. ``tls/`` listeners need an identity (the
drone's certificate); with one, the router also enforces access control generated from the
registry and the key store (:mod:`dronewrapper.security.acl`), deny by default.
"""

from __future__ import annotations

import ipaddress
import logging
import threading

from dronewrapper.runtime.node import open_session
from dronewrapper.runtime.options import DEFAULT_ROUTER, ZenohOptions

log = logging.getLogger("router")

PLAIN_PROTOCOLS = ("tcp", "udp", "ws")
LOOPBACK_NAMES = ("localhost", "ip6-localhost")


class InsecureEndpoint(ValueError):
    """A plain listener on a non-loopback address, without ``insecure``."""


def is_loopback(endpoint: str) -> bool:
    """True if ``endpoint`` (``PROTO/HOST:PORT``) listens on loopback only."""
    address = endpoint.split("/", 1)[1].split("#", 1)[0]
    host = address.rsplit(":", 1)[0].strip("[]")
    if host in LOOPBACK_NAMES:
        return True
    try:
        return ipaddress.ip_address(host).is_loopback
    except ValueError:
        return False  # a host name or an interface: assume it leaves the machine


def check_endpoints(listen: list[str], *, identity: str, insecure: bool) -> None:
    """Refuse what would hand the drone to the network (the message says why and what to do)."""
    for endpoint in listen:
        proto = endpoint.split("/", 1)[0]
        if proto in PLAIN_PROTOCOLS and not is_loopback(endpoint) and not insecure:
            raise InsecureEndpoint(
                f"refusing to listen on {endpoint}: plain {proto} off loopback lets anyone on "
                "that network command the drone. Listen on tls/ with the drone's certificate "
                "(--identity NAME, see `dronewrapper keys`), or pass --insecure on a network "
                "you trust"
            )
        if proto in ("tls", "quic") and not identity:
            raise InsecureEndpoint(f"{endpoint} needs --identity (the drone's certificate)")


def router_options(
    listen: list[str] | None = None,
    connect: list[str] | None = None,
    *,
    identity: str = "",
    keys_dir: str = "",
    insecure: bool = False,
    acl_namespaces: list[str] | None = None,
) -> ZenohOptions:
    """Options for a router listening on ``listen`` (default loopback 7447).

    With an ``identity``, access control is on: the policy comes from the registry and the key
    store's valid certificates (``acl_namespaces`` limits it to those vehicles).

    Raises:
        InsecureEndpoint: a plain listener off loopback without ``insecure``, or a TLS
            listener without an identity.
    """
    listen = list(listen or [DEFAULT_ROUTER])
    check_endpoints(listen, identity=identity, insecure=insecure)
    acl = None
    if identity:
        from dronewrapper.security.acl import access_control
        from dronewrapper.security.keystore import KeyStore

        acl = access_control(KeyStore(keys_dir or None).names_by_role(), acl_namespaces)
    return ZenohOptions(
        mode="router",
        listen=listen,
        connect=list(connect or []),
        identity=identity,
        keys_dir=keys_dir,
        access_control=acl,
    )


def run_router(
    options: ZenohOptions, stop: threading.Event, ready: threading.Event | None = None
) -> None:
    """Run a router until ``stop`` is set, then close it."""
    session = open_session(options)
    try:
        acl = (
            "access control on (deny by default)" if options.access_control else "no access control"
        )
        log.info("router %s listening on %s; %s", session.zid(), ", ".join(options.listen), acl)
        if ready is not None:
            ready.set()
        while not stop.wait(0.5):
            pass
    finally:
        session.close()
