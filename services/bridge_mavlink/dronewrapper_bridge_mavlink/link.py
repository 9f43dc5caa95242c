"""The MAVLink connection: open by pymavlink URL, thread-safe sends, reopen after errors.

URLs as pymavlink takes them: ``udpin:127.0.0.1:14540`` (listen; replies go to whoever sent),
``udpout:HOST:PORT``, ``tcp:HOST:PORT`` (client, reconnects), ``tcpin:127.0.0.1:PORT``, or a
serial device (``/dev/ttyACM0``) with ``baud``. MAVLink 2 is used for everything we send.
A network link beyond loopback is a deliberate setting (see :func:`network_exposure`).

With a signing key (``signing_key_file``, made by ``dronewrapper keys mavlink``) every message
we send is signed (MAVLink 2 signing: SHA-256 over the frame and a 48-bit timestamp in 10 µs
units since 2015) and every message received must carry a valid signature with a timestamp
newer than the last one of its stream; unsigned, wrongly signed or replayed messages are
dropped and counted (``rejected``), except RADIO_STATUS, which radios insert unsigned. A keyed
link never falls back to MAVLink 1 (it cannot carry a signature).
"""

from __future__ import annotations

import ipaddress
import logging
import os
import threading
import time
from typing import Any, NamedTuple

os.environ.setdefault("MAVLINK20", "1")

import contextlib

from pymavlink import mavutil

from dronewrapper.security.mavlink_signing import verify_signed_frame
from dronewrapper_bridge_mavlink.link_budget import NETWORK_SCHEMES

log = logging.getLogger("bridge_mavlink.link")

UNSIGNED_ALLOWED = frozenset({mavutil.mavlink.MAVLINK_MSG_ID_RADIO_STATUS})  # radios add it
UDP_CLIENT_TIMEOUT_S = 5.0  # udpin: stop sending to a peer silent for this long (restarted sim)


def network_exposure(url: str) -> str | None:
    """Why ``url`` reaches beyond this machine (a sentence for the log), or None for loopback
    and serial links. ``udpin:0.0.0.0:P`` listens on every interface and answers whoever sent
    last; a host name is not loopback unless it is ``localhost``."""
    scheme, sep, rest = url.partition(":")
    if not sep or scheme not in NETWORK_SCHEMES:
        return None  # a serial device
    host = rest.rsplit(":", 1)[0].strip("[]")
    if host == "localhost":
        return None
    try:
        address = ipaddress.ip_address(host)
    except ValueError:
        return f"{url}: host {host!r} is not a loopback address"
    if address.is_loopback:
        return None
    if address.is_unspecified:
        return f"{url} listens on every network interface (not only loopback)"
    return f"{url} talks to {host}, beyond this machine"


class _SourceNotingSocket:
    """A UDP socket that records on ``owner.last_source`` where each datagram came from."""

    def __init__(self, sock: Any, owner: MavLink) -> None:
        self._sock = sock
        self._owner = owner

    def recvfrom(self, size: int) -> tuple[bytes, Any]:
        data, address = self._sock.recvfrom(size)
        self._owner.last_source = address
        return data, address

    def __getattr__(self, name: str) -> Any:
        return getattr(self._sock, name)


class MavLink:
    """One MAVLink connection with a send lock (sends come from several threads).

    Args:
        url: pymavlink connection string.
        baud: serial baud rate (ignored for network URLs).
        source_system, source_component: our MAVLink ids.
        signing_key_file: the 32-byte MAVLink 2 signing key (64 hex digits); "" = unsigned.
    """

    def __init__(
        self,
        url: str,
        *,
        baud: int = 57600,
        source_system: int = 255,
        source_component: int = 190,
        signing_key_file: str = "",
    ) -> None:
        self.signing_key: bytes | None = None
        if signing_key_file:
            from dronewrapper.security.keystore import read_mavlink_key

            self.signing_key = read_mavlink_key(signing_key_file)
        self.url = url
        self.baud = baud
        self.source_system = source_system
        self.source_component = source_component
        self._send_lock = threading.Lock()
        self._conn: Any = None
        self._t0 = time.monotonic()
        self.last_source: Any = None  # (host, port) the last message came from (UDP), else None
        self.peer: Any = None  # UDP listen: the address replies go to (None: the last sender)
        self.sent = 0
        self.send_errors = 0
        self._closed_counts = LinkCounts(0, 0, 0)  # what connections closed before counted

    @property
    def mav(self) -> Any:
        """The pymavlink MAVLink encoder (only use it under :meth:`send`)."""
        return self._conn.mav

    def open(self) -> None:
        """Open the connection (raises OSError/ValueError when it cannot be opened)."""
        kwargs: dict[str, Any] = {
            "source_system": self.source_system,
            "source_component": self.source_component,
            "autoreconnect": True,
            "robust_parsing": True,
        }
        if self.url.startswith("udpin:") or self.url.startswith("udp:"):
            kwargs["udp_timeout"] = UDP_CLIENT_TIMEOUT_S
        if not any(self.url.startswith(p) for p in ("udp", "tcp")):
            kwargs["baud"] = self.baud
        conn = mavutil.mavlink_connection(self.url, **kwargs)
        if hasattr(conn, "mav"):
            conn.mav.robust_parsing = True
        if getattr(conn, "udp_server", False):
            self._track_udp_peers(conn)
        if self.signing_key is not None:
            if not conn.mavlink20():
                conn.close()
                raise ValueError("MAVLink signing needs MAVLink 2 (MAVLINK20=1), not MAVLink 1")
            conn.setup_signing(
                self.signing_key, sign_outgoing=True, allow_unsigned_callback=_allow_unsigned
            )
            signing = conn.mav.signing  # PX4's order: a forged frame cannot block the stream
            conn.mav.check_signature = lambda buf, sysid, compid: verify_signed_frame(
                signing, buf, sysid, compid
            )
        self._conn = conn

    def _track_udp_peers(self, conn: Any) -> None:
        """Note each datagram's source address; send only to ``peer`` once it is set."""
        conn.port = _SourceNotingSocket(conn.port, self)
        send_to_all = conn.write

        def write(buf: bytes) -> None:
            peer = self.peer
            if peer is None:
                send_to_all(buf)
            else:
                conn.port.sendto(buf, peer)

        conn.write = write

    @property
    def rejected(self) -> int:
        """Messages dropped for a missing, wrong or replayed signature (keyed links)."""
        conn = self._conn
        if conn is None or self.signing_key is None:
            return 0
        signing = conn.mav.signing
        return int(signing.reject_count)

    def counts(self) -> LinkCounts:
        """Bytes received and sent, and frames lost, since this link was made (over reopens).

        Frames lost are gaps in the autopilot's MAVLink sequence numbers plus bytes that did
        not parse (pymavlink's counts)."""
        return self._closed_counts + _counts_of(self._conn)

    def close(self) -> None:
        """Close the connection (idempotent)."""
        conn, self._conn = self._conn, None
        if conn is not None:
            self._closed_counts = self._closed_counts + _counts_of(conn)
            with contextlib.suppress(OSError):
                conn.close()

    @property
    def is_open(self) -> bool:
        return self._conn is not None

    def recv(self, timeout: float) -> Any:
        """The next message, or None after ``timeout`` s (raises OSError on a link error).

        ``last_source`` is then the UDP address it came from. When ``peer`` is set, replies of
        a listening UDP link keep going to it even if someone else sent last (pymavlink would
        send to every recent sender: a second autopilot would receive our commands).

        A UDP link waits in ``select`` only when nothing is buffered and reads once per
        wake-up (pymavlink's ``recv_match`` reads again after every message: a failed
        non-blocking read per datagram); serial and TCP links go through ``recv_match``, which
        also reconnects a TCP link whose socket was replaced."""
        conn = self._conn
        if conn is None:
            time.sleep(timeout)
            return None
        if not isinstance(conn, mavutil.mavudp):
            return conn.recv_match(blocking=True, timeout=timeout)
        deadline = time.monotonic() + timeout
        buffered = conn.mav.buf_len() > 0  # the rest of a datagram or stream read before
        while True:
            if not buffered and not conn.select(max(0.0, deadline - time.monotonic())):
                return None
            msg = conn.recv_msg()
            if msg is not None:
                return msg
            if time.monotonic() >= deadline:
                return None
            buffered = False  # what is left is part of a frame: wait for more bytes

    def time_boot_ms(self) -> int:
        """Milliseconds since this link was created (our ``time_boot_ms``)."""
        return int((time.monotonic() - self._t0) * 1000) & 0xFFFFFFFF

    def write_raw(self, frame: bytes) -> None:
        """Write whole frames as they are (a ground station's, forwarded); raises OSError.

        On a signed link the ground station must sign with the same key (QGC can); the bridge
        does not re-sign frames it did not make."""
        conn = self._conn
        if conn is None:
            raise OSError("the autopilot link is not open")
        with self._send_lock:
            conn.write(frame)
            conn.mav.total_bytes_sent += len(frame)

    def send(self, name: str, *args: Any, **kwargs: Any) -> bool:
        """Send message ``name`` (e.g. ``heartbeat``) with its fields; False if not sent."""
        conn = self._conn
        if conn is None:
            return False
        with self._send_lock:
            try:
                getattr(conn.mav, f"{name}_send")(*args, **kwargs)
            except OSError as exc:
                self.send_errors += 1
                log.debug("send %s failed: %s", name, exc)
                return False
        self.sent += 1
        return True


class LinkCounts(NamedTuple):
    """Bytes received, bytes sent, frames lost (sequence gaps and unparsable bytes)."""

    received: int
    sent: int
    lost: int

    def __add__(self, other: tuple) -> LinkCounts:  # type: ignore[override]
        return LinkCounts(*(a + b for a, b in zip(self, other, strict=True)))


def _counts_of(conn: Any) -> LinkCounts:
    """pymavlink's counts of one connection (zeros for None)."""
    mav = getattr(conn, "mav", None)
    if mav is None:
        return LinkCounts(0, 0, 0)
    lost = int(getattr(conn, "mav_loss", 0)) + int(getattr(mav, "total_receive_errors", 0))
    return LinkCounts(int(mav.total_bytes_received), int(mav.total_bytes_sent), lost)


def _allow_unsigned(_mav: Any, msg_id: int) -> bool:
    """pymavlink's hook for a message without a valid signature: only RADIO_STATUS passes."""
    return msg_id in UNSIGNED_ALLOWED
