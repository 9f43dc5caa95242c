"""The simulator's UDP sockets: bound, non-blocking, and closed again when the bind fails."""

from __future__ import annotations

import socket


def bind_udp(address: str, port: int, what: str = "") -> socket.socket:
    """A non-blocking UDP socket bound to ``address:port`` (0: any free port). OSError when
    the address cannot be bound: ``what`` (the socket's use) and the address named in it, or,
    without ``what``, the system's own error."""
    sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    try:
        sock.bind((address, port))
    except OSError as exc:
        sock.close()
        if not what:
            raise
        raise OSError(f"{what}: cannot bind UDP {address}:{port}: {exc.strerror}") from exc
    sock.setblocking(False)
    return sock
