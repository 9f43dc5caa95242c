"""Zenoh session options: the one place where every process's session is configured.

Every process takes the same flags (``--connect``, ``--listen``, ``--mode``, ``--namespace``,
``--name``, ``--identity``) with the same environment fallbacks (``DRONEWRAPPER_CONNECT``,
``..._LISTEN``, ``..._MODE``, ``..._NAMESPACE``, ``..._IDENTITY``). An identity (a certificate
from ``dronewrapper keys``) makes the session speak mutual TLS on ``tls/`` endpoints.
Multicast scouting is always off: processes find each other
through a router on explicit endpoints, and local peers then link directly (gossip through the
router), so images between processes on one machine go peer to peer over shared memory.
"""

from __future__ import annotations

import json
import os
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import zenoh

from dronewrapper.msgs.registry import DEFAULT_NAMESPACE

if TYPE_CHECKING:
    import argparse  # the command-line helpers' types; a node never parses arguments

DEFAULT_ROUTER = "tcp/127.0.0.1:7447"
MODES = ("peer", "client", "router")
ENV_PREFIX = "DRONEWRAPPER_"


@dataclass
class ZenohOptions:
    """How a process joins the Zenoh network.

    Attributes:
        mode: ``peer`` (services on the drone: direct links to local peers), ``client`` (a
            laptop or a light tool: everything through the router) or ``router``.
        connect: endpoints to connect to, e.g. ``["tcp/127.0.0.1:7447"]``.
        listen: endpoints to listen on; peers default to an ephemeral loopback port.
        namespace: the vehicle namespace that prefixes every key (``drone``, ``drone2`` ...).
        name: the process's name for its liveliness token ``{ns}/alive/{name}``.
        shared_memory: use Zenoh shared memory for large payloads between local processes.
        identity: a key-store name or a path to NAME.crt (see ``dronewrapper keys``): the
            certificate shown on ``tls/`` links, checked against the project CA both ways.
        keys_dir: the key store folder for ``identity`` (default ``$DRONEWRAPPER_KEYS`` or
            ``~/.config/dronewrapper/keys``).
        access_control: a Zenoh ``access_control`` section (routers; see
            ``dronewrapper.security.acl``).
        low_latency: speak Zenoh's low-latency transport where the other end does too (see
            :data:`LOW_LATENCY_CONFIG`): each message is written to the socket by the
            thread that puts it, with no batching, no priorities and no fragmentation
            (:data:`LOW_LATENCY_MAX_BYTES`). Only for sessions that stay on this machine,
            in processes that publish small messages (a controller, a bridge's
            setpoints), never a camera's.
    """

    mode: str = "peer"
    connect: list[str] = field(default_factory=lambda: [DEFAULT_ROUTER])
    listen: list[str] = field(default_factory=list)
    namespace: str = DEFAULT_NAMESPACE
    name: str = ""
    shared_memory: bool = True
    identity: str = ""
    keys_dir: str = ""
    access_control: dict[str, Any] | None = None
    low_latency: bool = False

    def __post_init__(self) -> None:
        if self.mode not in MODES:
            raise ValueError(f"zenoh mode must be one of {', '.join(MODES)}, got {self.mode!r}")
        if not self.namespace or "/" in self.namespace or "*" in self.namespace:
            raise ValueError(f"namespace must be one key chunk, got {self.namespace!r}")
        for endpoint in [*self.connect, *self.listen]:
            if "/" not in endpoint:
                raise ValueError(f"endpoint {endpoint!r} is not PROTO/ADDRESS (tcp/127.0.0.1:7447)")
        if self.low_latency and leaves_machine(self):
            raise ValueError(
                "low_latency is for sessions that stay on this machine (it turns priorities "
                "off, and a slow link needs them to put control before camera frames); "
                f"endpoints: {', '.join([*self.listen, *self.connect])}"
            )


def _split(value: str | None) -> list[str] | None:
    if value is None:
        return None
    return [part.strip() for part in value.split(",") if part.strip()]


def add_zenoh_args(parser: argparse.ArgumentParser, *, default_mode: str = "peer") -> None:
    """Add the common Zenoh flags to ``parser`` (defaults come from the environment)."""
    group = parser.add_argument_group("zenoh")
    group.add_argument(
        "--connect",
        action="append",
        metavar="ENDPOINT",
        help=f"endpoint to connect to, repeatable (env {ENV_PREFIX}CONNECT, "
        f"default {DEFAULT_ROUTER})",
    )
    group.add_argument(
        "--listen",
        action="append",
        metavar="ENDPOINT",
        help=f"endpoint to listen on, repeatable (env {ENV_PREFIX}LISTEN)",
    )
    group.add_argument(
        "--mode",
        choices=MODES,
        default=None,
        help=f"zenoh session mode (env {ENV_PREFIX}MODE, default {default_mode})",
    )
    group.add_argument(
        "--namespace",
        "--ns",
        default=None,
        help=f"vehicle namespace (env {ENV_PREFIX}NAMESPACE, default {DEFAULT_NAMESPACE})",
    )
    group.add_argument("--name", default="", help="process name for the liveliness token")
    group.add_argument(
        "--identity",
        default=None,
        metavar="NAME",
        help=f"certificate for tls/ endpoints, from `dronewrapper keys` (env {ENV_PREFIX}IDENTITY)",
    )
    parser.set_defaults(zenoh_default_mode=default_mode)
    group.add_argument(
        "--no-shm", action="store_true", help="disable Zenoh shared memory for large payloads"
    )
    group.add_argument(
        "--low-latency",
        action="store_true",
        default=None,
        help="Zenoh's low-latency transport on local links (no batching, no priorities; "
        f"env {ENV_PREFIX}LOW_LATENCY=1)",
    )


def options_from_args(args: argparse.Namespace, *, name: str = "") -> ZenohOptions:
    """Build ZenohOptions from parsed flags, falling back to the environment."""
    connect = args.connect or _split(os.environ.get(f"{ENV_PREFIX}CONNECT")) or [DEFAULT_ROUTER]
    listen = args.listen or _split(os.environ.get(f"{ENV_PREFIX}LISTEN")) or []
    env = os.environ
    default_mode = getattr(args, "zenoh_default_mode", "peer")
    return ZenohOptions(
        mode=args.mode or env.get(f"{ENV_PREFIX}MODE", default_mode),
        connect=connect,
        listen=listen,
        namespace=args.namespace or env.get(f"{ENV_PREFIX}NAMESPACE", DEFAULT_NAMESPACE),
        name=args.name or name,
        shared_memory=not args.no_shm,
        identity=getattr(args, "identity", None) or env.get(f"{ENV_PREFIX}IDENTITY", ""),
        low_latency=bool(getattr(args, "low_latency", None))
        or env.get(f"{ENV_PREFIX}LOW_LATENCY", "") in ("1", "true", "yes"),
    )


_LOCAL_HOSTS = ("127.", "localhost", "[::1]", "::1")


def is_local_endpoint(endpoint: str) -> bool:
    """True if a Zenoh endpoint (``tcp/127.0.0.1:7447``, ``unixsock-stream/...``) stays on
    this machine (pure).

    >>> is_local_endpoint("tcp/127.0.0.1:7447"), is_local_endpoint("tls/192.168.1.50:7447")
    (True, False)
    """
    protocol, _, address = endpoint.partition("/")
    if protocol.startswith("unixsock") or protocol == "unixpipe":
        return True
    host = address.split("#", 1)[0].rsplit(":", 1)[0]
    return host.startswith(_LOCAL_HOSTS)


SLOW_LINK_BATCH_BYTES = 8192
"""Zenoh batch size on links that leave this machine: a batch in flight delays everything
behind it (64 KB, the default, takes 105 ms at 5 Mbit/s; 8 KB takes 13 ms)."""
SLOW_LINK_SOCKET_BYTES = 16384
"""TCP socket buffers on links that leave this machine (the kernel doubles them). Bytes queued
in the kernel are beyond Zenoh's priorities: 1 MB of camera frames there made telemetry 1.7 s
late on a 5 Mbit/s link; 32 KB keeps it under 0.2 s."""


LOW_LATENCY_CONFIG = {"transport/unicast/lowlatency": True, "transport/unicast/qos/enabled": False}
"""Zenoh's low-latency unicast transport, and QoS off (which it requires). Both are negotiated
when a link opens: a link uses them only where both of its ends ask for them, so a
low-latency process still links to every other process, the ordinary way. On such a link a
put is written to the socket by the putting thread (no transmit thread, no batching) and all
priorities share one lane."""


LOW_LATENCY_MAX_BYTES = 64_000
"""The largest payload a low-latency session puts outside shared memory (bytes). The
low-latency transport does not fragment: a message over one batch (64 KiB less headers) that
does not travel in shared memory would be lost without a word, so the runtime's publishers
refuse it (ValueError). Images travel in shared memory and are not concerned while the pool
has room."""

LOW_LATENCY_RUNTIME = "(rx: (worker_threads: 1))"
"""Zenoh's receive runtime on one thread instead of two (``ZENOH_RUNTIME``, read once, when
a process opens its first session): a sample then wakes one receiving thread, not two. A
low-latency peer or client takes it unless ``ZENOH_RUNTIME`` is set; a router keeps two."""


def zenoh_runtime_env(options: ZenohOptions, environ: dict[str, str]) -> dict[str, str]:
    """The environment ``open_session`` adds before Zenoh starts its threads (pure)."""
    if options.low_latency and options.mode != "router" and "ZENOH_RUNTIME" not in environ:
        return {"ZENOH_RUNTIME": LOW_LATENCY_RUNTIME}
    return {}


def leaves_machine(options: ZenohOptions) -> bool:
    """True if this session listens on or connects to an endpoint beyond this machine."""
    return not all(is_local_endpoint(e) for e in [*options.listen, *options.connect])


def zenoh_config(options: ZenohOptions) -> zenoh.Config:
    """The zenoh.Config for ``options`` (multicast scouting off, explicit endpoints)."""
    conf = zenoh.Config()
    conf.insert_json5("mode", json.dumps(options.mode))
    listen = list(options.listen)
    if options.mode == "peer" and not listen:
        listen = ["tcp/127.0.0.1:0"]  # loopback only; never every interface by default
    conf.insert_json5("listen/endpoints", json.dumps(listen))
    connect = [] if options.mode == "router" and not options.connect else options.connect
    conf.insert_json5("connect/endpoints", json.dumps(connect))
    conf.insert_json5("scouting/multicast/enabled", "false")
    if options.mode == "router":
        # nothing to scout with multicast off: do not wait Zenoh's default 0.5 s at open
        conf.insert_json5("scouting/delay", "0")
    else:
        # keep trying the router in the background instead of failing the process
        conf.insert_json5("connect/exit_on_failure", "false")
    conf.insert_json5("transport/shared_memory/enabled", json.dumps(options.shared_memory))
    if options.low_latency:
        for key, value in LOW_LATENCY_CONFIG.items():
            conf.insert_json5(key, json.dumps(value))
    if leaves_machine(options):
        # camera frames must not sit in front of telemetry where priorities cannot reorder them
        conf.insert_json5("transport/link/tx/batch_size", str(SLOW_LINK_BATCH_BYTES))
        buffers = {"so_sndbuf": SLOW_LINK_SOCKET_BYTES, "so_rcvbuf": SLOW_LINK_SOCKET_BYTES}
        conf.insert_json5("transport/link/tcp", json.dumps(buffers))
    if options.identity:
        from dronewrapper.security.identity import Identity

        identity = Identity.load(options.identity, options.keys_dir or None)
        conf.insert_json5("transport/link/tls", json.dumps(identity.tls_config()))
    if options.access_control is not None:
        conf.insert_json5("access_control", json.dumps(options.access_control))
    return conf


def tcp_address(endpoint: str) -> tuple[str, int] | None:
    """``(host, port)`` of a ``tcp/`` or ``tls/`` endpoint, else None (pure).

    >>> tcp_address("tcp/127.0.0.1:7447"), tcp_address("tls/[::1]:7448#iface=lo")
    (('127.0.0.1', 7447), ('::1', 7448))
    """
    protocol, _, address = endpoint.partition("/")
    if protocol not in ("tcp", "tls"):
        return None
    host, _, port = address.split("#", 1)[0].split("?", 1)[0].rpartition(":")
    if not host or not port.isdigit():
        return None
    return host.strip("[]"), int(port)
