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

Reading pays only for what is read: each wake-up of the receive thread drains every datagram
waiting on a UDP socket (or every byte waiting on a serial or TCP link), cuts the bytes into
frames by their headers (:mod:`~dronewrapper_bridge_mavlink.wire`) and decodes only the frames
whose message id is in ``wanted``; the others are dropped undecoded (and handed, raw, to
``tap``, the ground-station forwarder, with every other frame). ``reading`` says how many
wake-ups, reads, frames and decoded messages that took. pymavlink's own counts, which
:meth:`MavLink.counts` reads (bytes received, sequence gaps, bad frames), are kept up to date
from the frames, decoded or not.
"""

from __future__ import annotations

import ipaddress
import logging
import os
import sys
import threading
from typing import Any, NamedTuple

os.environ.setdefault("MAVLINK20", "1")
os.environ.setdefault("MAVLINK_DIALECT", "common")  # what the bridge reads and sends; "all"
# (pymavlink's default) would load a second, larger copy of the message tables
if "pymavlink.dialects.v10.all" not in sys.modules:  # mavutil imports MAVLink 1's "all" only
    # for freezers, and lets it fail (6 MB); typeshed allows only modules in sys.modules
    sys.modules["pymavlink.dialects.v10.all"] = None  # type: ignore[assignment]

import contextlib
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass

from pymavlink import mavutil

from dronewrapper.runtime.clock import REAL, Clock
from dronewrapper.security.mavlink_signing import verify_signed_frame
from dronewrapper_bridge_mavlink.link_budget import NETWORK_SCHEMES
from dronewrapper_bridge_mavlink.outgoing import Send, encode
from dronewrapper_bridge_mavlink.wire import Frame, FrameCutter, SequenceGaps, cut_datagram

log = logging.getLogger("bridge_mavlink.link")

UNSIGNED_ALLOWED = frozenset({mavutil.mavlink.MAVLINK_MSG_ID_RADIO_STATUS})  # radios add it
UDP_CLIENT_TIMEOUT_S = 5.0  # udpin: stop sending to a peer silent for this long (restarted sim)
MAX_READS_PER_WAKEUP = 256  # datagrams (or stream reads) drained per wake-up, at most
STREAM_READ_BYTES = 4096  # one read of a serial or TCP link


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


@dataclass
class ReadCounts:
    """What the receive side did since the link was made: ``wakeups`` (select returned),
    ``reads`` (datagrams or stream reads), ``frames`` cut, ``decoded`` messages, ``dropped``
    undecoded for their id, ``bad`` frames that failed to decode (CRC, signature, length)."""

    wakeups: int = 0
    reads: int = 0
    frames: int = 0
    decoded: int = 0
    dropped: int = 0
    bad: int = 0


@dataclass(frozen=True)
class Received:
    """One decoded message and the UDP address it came from (None on serial and TCP)."""

    msg: Any
    source: Any


class MavLink:
    """One MAVLink connection with a send lock (sends come from several threads).

    Args:
        url: pymavlink connection string.
        baud: serial baud rate (ignored for network URLs).
        source_system, source_component: our MAVLink ids.
        signing_key_file: the 32-byte MAVLink 2 signing key (64 hex digits); "" = unsigned.
        wanted: the message ids to decode (the others are dropped before decoding); None:
            decode every frame.
        clock: the node's clock (a wait with no connection open waits on it).
    """

    def __init__(
        self,
        url: str,
        *,
        baud: int = 57600,
        source_system: int = 255,
        source_component: int = 190,
        signing_key_file: str = "",
        wanted: frozenset[int] | None = None,
        clock: Clock = REAL,
    ) -> None:
        self.wanted = wanted
        self.tap: Callable[[bytes], None] | None = None
        """Called with every frame's bytes as received, decoded or not (forwarding)."""
        self.reading = ReadCounts()
        self._cutter = FrameCutter()
        self._gaps = SequenceGaps()
        self._pending: deque[Received] = deque()
        self._socket: Any = None  # a TCP link's socket (a new one after a reconnect)
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
        self._clock = clock
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
        self._cutter.clear()
        self._pending.clear()
        self._gaps = SequenceGaps()  # a new connection: each sender's count starts afresh
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
        """The next message, or None after ``timeout`` s (raises OSError on a link error);
        ``last_source`` is then the UDP address it came from. One message at a time from
        :meth:`recv_batch`."""
        if not self._pending:
            self._pending.extend(self.recv_batch(timeout))
        if not self._pending:
            return None
        received = self._pending.popleft()
        self.last_source = received.source
        return received.msg

    def recv_batch(self, timeout: float) -> list[Received]:
        """Every wanted message that arrived by one wake-up, in order; [] after ``timeout`` s
        with nothing wanted (raises OSError on a link error).

        Waits in ``select`` once, then drains the link: every datagram waiting on a UDP socket
        (each one's frames with its source address), or every byte waiting on a serial or TCP
        link (a frame cut across reads is kept for the next one). When ``peer`` is set, replies
        of a listening UDP link keep going to it even if someone else sent last (pymavlink
        would send to every recent sender: a second autopilot would receive our commands)."""
        conn = self._conn
        if conn is None:
            self._clock.sleep(timeout)
            return []
        if isinstance(conn, mavutil.mavtcp) and (port := _tcp_socket(conn)) is not self._socket:
            self._socket = port  # a new connection: what the old one left of a frame is none
            self._cutter.clear()
        if not conn.select(max(0.0, timeout)):
            return []
        return self.drain()

    @property
    def is_udp(self) -> bool:
        """A UDP link is open (one socket, which :meth:`fileno` gives, for the whole link)."""
        return isinstance(self._conn, mavutil.mavudp)

    def fileno(self) -> int:
        """The descriptor of an open UDP link's socket (to wait on), else -1."""
        conn = self._conn
        return conn.port.fileno() if isinstance(conn, mavutil.mavudp) else -1

    def drain(self) -> list[Received]:
        """Every wanted message waiting now, without waiting (see :meth:`recv_batch`); raises
        OSError on a link error."""
        conn = self._conn
        if conn is None:
            return []
        self.reading.wakeups += 1
        datagrams = isinstance(conn, mavutil.mavudp)
        out: list[Received] = []
        for _ in range(MAX_READS_PER_WAKEUP):
            data = conn.recv() if datagrams else conn.recv(STREAM_READ_BYTES)
            if not data:
                break
            self.reading.reads += 1
            conn.mav.total_bytes_received += len(data)
            skipped = self._cutter.skipped
            if datagrams:
                self._decode(conn, cut_datagram(data, self._cutter), self.last_source, out)
            else:
                self._decode(conn, self._cutter.feed(data), None, out)
            if self._cutter.skipped > skipped:  # bytes that were no frame: an error, as
                conn.mav.total_receive_errors += 1  # pymavlink counts a bad prefix
        return out

    def _decode(self, conn: Any, frames: list[Frame], source: Any, out: list[Received]) -> None:
        """Decode the wanted ``frames`` into ``out``; hand every frame to ``tap``."""
        counts, wanted, tap, gaps = self.reading, self.wanted, self.tap, self._gaps
        counts.frames += len(frames)
        for frame in frames:
            conn.mav_loss += gaps.add(frame.data)
            if tap is not None:
                tap(frame.data)
            if wanted is not None and frame.msg_id not in wanted:
                counts.dropped += 1
                continue
            try:
                msg = conn.mav.decode(bytearray(frame.data))
            except mavutil.mavlink.MAVError:
                counts.bad += 1
                conn.mav.total_receive_errors += 1
                continue
            counts.decoded += 1
            out.append(Received(msg, source))

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

    def send(self, message: Send) -> bool:
        """Encode and send one of the bridge's messages (:mod:`.outgoing`); False if not sent."""
        conn = self._conn
        if conn is None:
            return False
        encoded = encode(message)
        with self._send_lock:
            try:
                conn.mav.send(encoded)
            except OSError as exc:
                self.send_errors += 1
                log.debug("send %s failed: %s", type(message).__name__, exc)
                return False
        self.sent += 1
        return True


def _tcp_socket(conn: Any) -> Any:
    """The socket a TCP link has now, which ``select`` then waits on: pymavlink reconnects the
    link inside ``recv`` (after the peer closed it) with a new socket but keeps the old one's
    descriptor in ``fd``."""
    if conn.port is None:  # the last reconnect failed: try again (OSError when it fails)
        conn.reconnect()
    if conn.port is None:
        raise OSError(f"{conn.address}: the TCP link is closed")
    conn.fd = conn.port.fileno()
    return conn.port


class LinkCounts(NamedTuple):
    """Bytes received, bytes sent, frames lost (sequence gaps and unparsable bytes)."""

    received: int
    sent: int
    lost: int

    def __add__(self, other: tuple) -> LinkCounts:
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
