"""MAVLink over UDP as PX4 SITL does it: one socket per link, replies to whoever talks to it.

A link binds a local port (0 = ephemeral) and sends to a default remote (127.0.0.1:14540 for the
onboard/API link, 127.0.0.1:14550 for the GCS link); as soon as a datagram arrives, the sender's
address becomes the remote. Messages are MAVLink 2 (pymavlink's ``common`` dialect), from system
``sysid`` component 1, the messages of one wake-up in as few datagrams as fit; bytes that do not
parse are counted and dropped. Each datagram is parsed on its own (a UDP datagram carries whole
frames), so a datagram that ends in a partial or bogus frame header cannot swallow the start of
the next one.

With a signing key (:meth:`MavlinkUdpLink.set_signing_key`, policy in ``px4/signing.py``) the
link signs what it sends and drops what arrives unsigned, wrongly signed or replayed
(``rejected`` counts them); its signing state (key, stream timestamps) outlives each datagram.
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from dataclasses import dataclass

from pymavlink.dialects.v20 import common as mavlink

from dronewrapper.security.mavlink_signing import verify_signed_frame
from dronewrapper_sim.udp import bind_udp

log = logging.getLogger("sim.mavlink")

ONBOARD_REMOTE_PORT = 14540
ONBOARD_LOCAL_PORT = 14580
GCS_REMOTE_PORT = 14550
GCS_LOCAL_PORT = 18570
LOOPBACK = "127.0.0.1"


@dataclass(frozen=True)
class UdpEndpoint:
    """Where a link sends by default (``remote_host:remote_port``) and its own local port."""

    remote_host: str
    remote_port: int
    local_port: int

    def __str__(self) -> str:
        return f"{self.remote_host}:{self.remote_port} from :{self.local_port or 'any'}"


def default_endpoints(instance: int = 0) -> dict[str, UdpEndpoint]:
    """PX4 SITL's links for instance ``instance`` (like ``px4 -i N``): the onboard link sends to
    14540+N from 14580+N; the GCS link sends to 14550 (every instance: ground stations listen
    there and tell vehicles apart by system id) from 18570+N."""
    if instance < 0:
        raise ValueError(f"instance must be >= 0, got {instance}")
    return {
        "onboard": UdpEndpoint(
            LOOPBACK, ONBOARD_REMOTE_PORT + instance, ONBOARD_LOCAL_PORT + instance
        ),
        "gcs": UdpEndpoint(LOOPBACK, GCS_REMOTE_PORT, GCS_LOCAL_PORT + instance),
    }


def _port(text: str, what: str) -> int:
    try:
        port = int(text)
    except ValueError:
        raise ValueError(f"{what} {text!r} is not a port number") from None
    if not 0 <= port <= 65535:
        raise ValueError(f"{what} {port} is out of range 0..65535")
    return port


def parse_udp_spec(spec: str, default_local: int) -> UdpEndpoint | None:
    """Parse ``[HOST:]PORT[:LOCAL]`` (``off`` disables the link; LOCAL 0 = ephemeral).

    >>> parse_udp_spec("15000:0", 14580)
    UdpEndpoint(remote_host='127.0.0.1', remote_port=15000, local_port=0)
    >>> parse_udp_spec("10.0.0.2:14550", 18570)
    UdpEndpoint(remote_host='10.0.0.2', remote_port=14550, local_port=18570)
    """
    text = spec.strip()
    if text.lower() in ("off", "none", "no", "false"):
        return None
    parts = text.split(":")
    if len(parts) == 1:
        return UdpEndpoint(LOOPBACK, _port(parts[0], "remote port"), default_local)
    if len(parts) == 2:
        if parts[0].isdigit():
            return UdpEndpoint(
                LOOPBACK, _port(parts[0], "remote port"), _port(parts[1], "local port")
            )
        return UdpEndpoint(parts[0], _port(parts[1], "remote port"), default_local)
    if len(parts) == 3:
        return UdpEndpoint(parts[0], _port(parts[1], "remote port"), _port(parts[2], "local port"))
    raise ValueError(f"UDP link {spec!r} is not [HOST:]PORT[:LOCAL] or 'off'")


DATAGRAM_BYTES = 1400
"""The most bytes of frames one datagram carries (within an Ethernet MTU beyond loopback)."""
SIGNING_EPOCH_S = 1420070400  # 2015-01-01T00:00:00Z, MAVLink signing timestamps count from here


def signing_timestamp(now_s: float) -> int:
    """A MAVLink signing timestamp (10 µs units since 2015) for Unix time ``now_s``."""
    return int((now_s - SIGNING_EPOCH_S) * 100_000)


class VerifyingMAVLink(mavlink.MAVLink):
    """pymavlink's parser with PX4's order of signature checks (see
    ``dronewrapper.security.mavlink_signing``): a stream's timestamp moves only when a
    signature is valid."""

    def check_signature(self, msgbuf: bytearray, srcSystem: int, srcComponent: int) -> bool:
        return verify_signed_frame(self.signing, msgbuf, srcSystem, srcComponent)


def parse_datagram(
    data: bytes, signing: mavlink.MAVLinkSigning | None = None
) -> list[mavlink.MAVLink_message]:
    """The MAVLink messages in one datagram, parsed on their own: bytes left over at its end
    (a truncated frame, or garbage that looks like a frame header) are dropped with it instead
    of waiting for the next datagram. Unparsable bytes come back as BAD_DATA messages, and so
    do messages ``signing`` rejects (a link's signing state, shared across datagrams)."""
    parser = VerifyingMAVLink(None)
    parser.robust_parsing = True
    if signing is not None:
        parser.signing = signing
    return parser.parse_buffer(data) or []


class MavlinkUdpLink:
    """One MAVLink link on a UDP socket (non-blocking; poll it with ``select`` on ``fileno``)."""

    def __init__(self, name: str, endpoint: UdpEndpoint, sysid: int, compid: int = 1) -> None:
        self.name = name
        self.endpoint = endpoint
        self.remote: tuple[str, int] = (endpoint.remote_host, endpoint.remote_port)
        loopback = endpoint.remote_host in (LOOPBACK, "localhost")
        address = LOOPBACK if loopback else "0.0.0.0"
        self.sock = bind_udp(address, endpoint.local_port, f"MAVLink {name} link")
        self.local_port: int = self.sock.getsockname()[1]
        self.mav = mavlink.MAVLink(None, srcSystem=sysid, srcComponent=compid)
        self.received = 0
        self.sent = 0  # messages
        self.datagrams = 0  # datagrams sent (several messages each)
        self.bad = 0
        self.send_errors = 0

    def set_signing_key(
        self, key: bytes | None, allow_unsigned: Callable[[int], bool], now: float
    ) -> None:
        """Sign what we send and verify what arrives with ``key`` (None: signing off); our
        signing timestamps start no earlier than ``now`` (Unix s, the simulator's clock)."""
        signing = self.mav.signing
        signing.secret_key = key
        signing.sign_outgoing = key is not None
        signing.allow_unsigned_callback = None if key is None else (lambda _m, i: allow_unsigned(i))
        signing.timestamp = max(signing.timestamp, signing_timestamp(now))
        signing.link_id = 0

    @property
    def rejected(self) -> int:
        """Messages dropped for a missing, wrong or replayed signature."""
        return int(self.mav.signing.reject_count)

    def fileno(self) -> int:
        return self.sock.fileno()

    def receive(self) -> list[mavlink.MAVLink_message]:
        """Every message waiting on the socket (the last sender becomes the remote)."""
        out: list[mavlink.MAVLink_message] = []
        for _ in range(256):  # bounded: at most 256 datagrams per call
            try:
                data, addr = self.sock.recvfrom(65535)
            except (BlockingIOError, InterruptedError):
                break
            except OSError as exc:  # e.g. ICMP port unreachable reported on some systems
                log.debug("%s link: recv error %s", self.name, exc)
                break
            self.remote = (addr[0], addr[1])
            try:
                msgs = parse_datagram(data, self.mav.signing)
            except Exception as exc:  # never let bad bytes end the link
                self.bad += 1
                log.debug("%s link: unparsable datagram: %s", self.name, exc)
                continue
            for msg in msgs:
                if msg.get_type() in ("BAD_DATA", "UNKNOWN"):
                    self.bad += 1
                    continue
                self.received += 1
                out.append(msg)
        return out

    def send(self, msgs: list[mavlink.MAVLink_message]) -> None:
        """Pack ``msgs`` and send them to the current remote, as few datagrams as fit in
        :data:`DATAGRAM_BYTES` each (a wake-up's telemetry in one: one system call here, one
        read at the receiver; MAVLink over UDP allows several frames a datagram)."""
        batch = bytearray()
        for msg in msgs:
            buf = msg.pack(self.mav)
            self.mav.seq = (self.mav.seq + 1) % 256
            if batch and len(batch) + len(buf) > DATAGRAM_BYTES:
                self._send_datagram(batch)
                batch = bytearray()
            batch += buf
            self.sent += 1
        if batch:
            self._send_datagram(batch)

    def _send_datagram(self, data: bytearray) -> None:
        try:
            self.sock.sendto(data, self.remote)
            self.datagrams += 1
        except OSError:
            self.send_errors += 1

    def close(self) -> None:
        self.sock.close()
