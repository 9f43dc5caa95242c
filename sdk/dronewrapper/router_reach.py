"""Whether a router listens where a command looks for one, asked with one TCP connect each
(milliseconds): ``echo``, ``alive``, ``record``, ``doctor`` and ``up --use-router`` fail at
once, saying what to do, instead of retrying a session for seconds and printing Zenoh's error.

Only a refused connection counts as "no router": an endpoint that answers, one that does not
answer in time (a far network, a firewall) and one that is not TCP (``udp/``, ``unixsock``) are
left to the session, which retries and reports on its own.
"""

from __future__ import annotations

import socket
from collections.abc import Callable, Sequence

import zenoh

from dronewrapper.runtime.node import open_session
from dronewrapper.runtime.options import ZenohOptions, tcp_address

NO_ROUTER_HINT = (
    "start one with `dronewrapper up compose/GRAPH.yaml` (or `dronewrapper router`), "
    "or point --connect at the one that runs"
)
PROBE_TIMEOUT_S = 1.0
"""Seconds one TCP connect may take before the endpoint is left to the session."""


def refuses(address: tuple[str, int], timeout: float = PROBE_TIMEOUT_S) -> bool:
    """True if nothing listens at ``address``: the connection was refused at once."""
    try:
        with socket.create_connection(address, timeout=timeout):
            return False
    except ConnectionRefusedError:
        return True
    except OSError:  # unreachable, timed out, unknown host: the session will say
        return False


def no_router(
    endpoints: Sequence[str], refused: Callable[[tuple[str, int]], bool] = refuses
) -> str | None:
    """A sentence when no router listens at any of ``endpoints`` (every one a TCP endpoint
    that refused a connection), else None."""
    addresses = [tcp_address(endpoint) for endpoint in endpoints]
    if not endpoints or None in addresses:
        return None
    if not all(refused(address) for address in addresses):
        return None
    where = ", ".join(endpoints)
    return f"no router at {where} (connection refused): {NO_ROUTER_HINT}"


def open_client_session(options: ZenohOptions, *, timeout: float = 10.0) -> zenoh.Session:
    """:func:`open_session` for a command that needs a router: fails at once when none listens.

    Raises:
        ConnectionError: no router listens at ``options.connect`` (with what to do), or no
            session could be opened within ``timeout`` seconds.
    """
    if options.mode == "client" and (sentence := no_router(options.connect)):
        raise ConnectionError(sentence)
    return open_session(options, timeout=timeout)


def why_no_session(connect: str, timeout: float, exc: BaseException) -> str:
    """The sentence for a client session that did not open on ``connect`` within ``timeout``
    s, failing with ``exc``: a refused TLS handshake says why, a refused connection says no
    router listens, and otherwise what was seen."""
    from dronewrapper.runtime.session import HandshakeRefused

    if isinstance(exc, HandshakeRefused):
        return str(exc)
    address = tcp_address(connect)
    if address is not None and refuses(address):
        return (
            f"cannot reach the Zenoh router at {connect}: nothing listens there (connection "
            f"refused); {NO_ROUTER_HINT}"
        )
    if address is not None:
        return (
            f"the router at {connect} took the connection but no Zenoh session opened within "
            f"{timeout:g} s ({exc})"
        )
    return f"cannot reach the Zenoh router at {connect} within {timeout:g} s: {NO_ROUTER_HINT}"
