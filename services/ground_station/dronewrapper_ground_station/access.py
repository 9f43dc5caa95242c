"""Who may do what on the station (pure: no sockets, no clocks).

Loopback is trusted (docs/security.md): a page opened on the station's own machine, through a
loopback address, is an operator's. From any other address a page is an operator's only with
the one-time token printed when the station starts; without it, an observer's: it watches and
never commands. What the station itself may do on a drone's router is its own certificate's
role (``--identity``), judged by the router's access control.

Two browser attacks are refused whatever the token: a page from another site sending commands
through the operator's browser (the ``Origin`` must be the station itself) and DNS rebinding (a
loopback client must have asked for a loopback host name).
"""

from __future__ import annotations

import hmac
import ipaddress
import secrets
from dataclasses import dataclass
from urllib.parse import urlsplit

OPERATOR = "operator"
OBSERVER = "observer"

LOOPBACK_NAMES = ("localhost",)


def is_loopback(host: str) -> bool:
    """Whether ``host`` (an address or a name, maybe ``[::1]``) is this machine's loopback."""
    host = host.strip().strip("[]").lower()
    if host in LOOPBACK_NAMES:
        return True
    try:
        return ipaddress.ip_address(host).is_loopback
    except ValueError:
        return False


def split_host(host_header: str) -> str:
    """The host name of a ``Host`` header value (``127.0.0.1:8080`` -> ``127.0.0.1``)."""
    value = host_header.strip()
    if value.startswith("["):
        return value[1 : value.find("]")] if "]" in value else value
    return value.rsplit(":", 1)[0] if value.count(":") == 1 else value


def new_token() -> str:
    """A fresh operator token (128 random bits, URL-safe)."""
    return secrets.token_urlsafe(16)


@dataclass(frozen=True)
class Access:
    """The station's access rule.

    Attributes:
        token: the operator token; "" when the station listens on loopback only (no token:
            only loopback clients exist and they are operators).
    """

    token: str = ""

    def role(self, client_host: str, host_header: str, presented_token: str) -> str:
        """``operator`` or ``observer`` for a request.

        Args:
            client_host: the peer address of the connection.
            host_header: the request's ``Host`` header.
            presented_token: the token the page sent ("" when none).
        """
        if (
            self.token
            and presented_token
            and hmac.compare_digest(presented_token.encode(), self.token.encode())
        ):
            return OPERATOR
        if is_loopback(client_host) and is_loopback(split_host(host_header)):
            return OPERATOR
        return OBSERVER

    @staticmethod
    def same_origin(origin: str | None, host_header: str) -> bool:
        """Whether a request's ``Origin`` is the station itself (absent: not a browser page
        of another site, e.g. a script; allowed)."""
        if origin is None:
            return True
        parts = urlsplit(origin)
        return parts.scheme in ("http", "https") and parts.netloc.lower() == host_header.lower()
