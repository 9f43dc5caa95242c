"""A plain Zenoh session: opening one, and request/reply and liveliness on it.

:class:`~dronewrapper.runtime.node.Node` stands on these; tools that hold a bare session (the
recorder, ``dronewrapper doctor``) use them directly. A service call asks again while its query
ends unanswered at once (a route not learnt yet), never beyond its timeout; an error reply comes
back as :class:`~dronewrapper.runtime.errors.ServiceError` with the server's message.
"""

from __future__ import annotations

import os
import time
from typing import TypeVar

import msgspec
import zenoh

from dronewrapper.msgs import codec
from dronewrapper.msgs.registry import ALIVE, Service
from dronewrapper.msgs.std import ErrorReply
from dronewrapper.runtime import caller
from dronewrapper.runtime.errors import (
    ServiceError,
    ServiceTimeout,
    ServiceUnavailable,
    zenoh_error_text,
)
from dronewrapper.runtime.options import ZenohOptions, zenoh_config, zenoh_runtime_env
from dronewrapper.runtime.qos import SERVICE_QOS

Req = TypeVar("Req")
Rep = TypeVar("Rep")

ERROR_ENCODING = zenoh.Encoding("application/msgpack").with_schema(codec.schema_name(ErrorReply))

ZENOH_QUERY_TIMEOUT = b"Timeout"
"""The error reply Zenoh itself gives a query whose server did not answer before its timeout."""

ROUTE_WAIT_S = 2.0
"""How long a service call keeps asking again while its query ends at once, unanswered (s).

Right after a session opens (or a server starts), Zenoh may not have learnt the server's
queryable yet; a query then finishes immediately with no reply. Asking again for a moment
(never beyond the call's timeout) covers that, so ``timeout`` means what it says."""


def encoding_for(msg_type: type) -> zenoh.Encoding:
    """The Zenoh encoding of a message type: ``application/msgpack;dronewrapper/v1/<Type>``."""
    return zenoh.Encoding("application/msgpack").with_schema(codec.schema_name(msg_type))


def open_session(options: ZenohOptions, *, timeout: float = 10.0) -> zenoh.Session:
    """Open a Zenoh session, retrying while the router is not up yet.

    A low-latency session's process runs Zenoh's receive runtime on one thread (see
    :data:`~dronewrapper.runtime.options.LOW_LATENCY_RUNTIME`; effective when it is the
    process's first session).

    Raises:
        ConnectionError: no session could be opened within ``timeout`` seconds.
    """
    added = zenoh_runtime_env(options, dict(os.environ))
    os.environ.update(added)  # read by Zenoh as it starts its threads, at the first open
    try:
        return _open(options, timeout)
    finally:
        for key in added:  # not for the processes this one starts
            os.environ.pop(key, None)


class HandshakeRefused(ConnectionError):
    """A TLS handshake with the router was refused; the message says by which side and why."""


RETRY_FIRST_S = 0.2
RETRY_MAX_S = 2.0
"""A session waiting for its router asks again after 0.2 s; on a ``tls/`` endpoint each wait is
twice the last, up to 2 s, so a router is not handed a failing handshake five times a second
(a refused handshake is not retried at all: certificates do not change while it waits)."""


def _open(options: ZenohOptions, timeout: float) -> zenoh.Session:
    deadline = time.monotonic() + timeout
    pause = RETRY_FIRST_S
    while True:
        try:
            return zenoh.open(zenoh_config(options))
        except zenoh.ZError as exc:
            # a router that cannot listen fails at once; a client/peer waits for its router
            where = ", ".join(options.connect or options.listen)
            if options.mode == "router" or time.monotonic() >= deadline:
                raise ConnectionError(
                    f"cannot open a zenoh {options.mode} session on {where}: "
                    f"{zenoh_error_text(exc)}"
                ) from exc
            if options.mode == "client":
                from dronewrapper.security.handshake import explain

                cause = explain(options.connect, options.identity, options.keys_dir)
                if cause is not None:
                    raise HandshakeRefused(cause) from exc
            time.sleep(max(0.0, min(pause, deadline - time.monotonic())))
            if any(e.startswith(("tls/", "quic/")) for e in options.connect):
                pause = min(pause * 2, RETRY_MAX_S)


def alive_services(session: zenoh.Session, ns: str = "*", timeout: float = 2.0) -> set[str]:
    """The concrete liveliness keys (``ns/alive/name``) present now, in ``ns`` or all."""
    keys = set()
    for reply in session.liveliness().get(ALIVE.wildcard(ns), timeout=timeout):
        if reply.ok is not None:
            keys.add(str(reply.ok.key_expr))
    return keys


def call_service(
    session: zenoh.Session,
    service: Service[Req, Rep],
    request: Req,
    *,
    ns: str,
    timeout: float = 5.0,
    attachment: bytes | None = None,
    bound_to: str = "",
    **parts: str,
) -> Rep:
    """Request/reply on a plain session (see :meth:`Node.call`); ``attachment`` travels with
    the request (the SDK names its commander there, see :mod:`dronewrapper.runtime.caller`);
    ``bound_to``: the certificate name the query's key is bound to (``KEY/@by/NAME``)."""
    if type(request) is not service.request:
        raise TypeError(
            f"{service.template} takes {service.request.__name__}, got {type(request).__name__}"
        )
    key = caller.bound_key(service.key(ns, **parts), bound_to)
    payload = codec.encode(request)
    start = time.monotonic()
    deadline = start + timeout
    ask_until = start + min(timeout, ROUTE_WAIT_S)
    while True:
        # A query that reached a server waits for its reply (up to the deadline); one that
        # reached none ends at once and is asked again until ``ask_until``.
        replies = session.get(
            key,
            payload=payload,
            encoding=encoding_for(service.request),
            timeout=max(0.001, deadline - time.monotonic()),
            **SERVICE_QOS,
            attachment=attachment,
        )
        for reply in replies:
            if reply.ok is not None:
                return codec.decode(service.reply, reply.ok.payload.to_bytes())
            raw = reply.err.payload.to_bytes()
            try:
                err = codec.decode(ErrorReply, raw)
            except (msgspec.DecodeError, msgspec.ValidationError):
                if raw == ZENOH_QUERY_TIMEOUT:
                    raise ServiceTimeout(
                        f"no reply from {key} within {timeout:g} s (Zenoh ended the query: "
                        f"the {service.server or 'server'} is busy, stuck or not running)",
                        time.monotonic() - start,
                    ) from None
                err = ErrorReply(message=raw.decode("utf-8", "replace"), code="internal")
            raise ServiceError(err.message, err.code)
        if time.monotonic() + 0.05 >= ask_until:
            break
        time.sleep(0.05)
    waited = time.monotonic() - start
    raise ServiceUnavailable(
        f"no reply from {key}: no server took the query in {waited:.1f} s: is the "
        f"{service.server or 'server'} running?",
        waited,
    )
