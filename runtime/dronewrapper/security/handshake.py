"""Why a TLS link to a router did not open, said from the side that knows.

Zenoh reports a failed TLS handshake to the client as "Unable to connect", and to the router as
a library warning that ends "Hint: increase the system open file limit" (its text for any
failed accept). This module names the cause instead:

- :func:`probe` (I/O) does one TLS handshake with the client's own files, the way Zenoh does,
  and :func:`client_sentence` (pure) says which side refused and why: this client refused the
  router's certificate (another CA, no identity), the router refused ours (none presented,
  expired, another CA), or the port speaks TLS while the client spoke plain tcp;
- :func:`router_meaning` (pure) turns one of Zenoh's accept warnings into what it means for the
  drone, and :class:`RejectionLog` lets each cause through once per interval, with a count.

Zenoh's warning names no peer address, so the router's log is rate-limited per cause.
"""

from __future__ import annotations

import contextlib
import socket
import ssl
from dataclasses import dataclass
from pathlib import Path

PROBE_TIMEOUT_S = 1.0
"""Seconds one probe's connect, handshake or first read may take."""

ACCEPTED = "accepted"  # the handshake completed and the router kept the link open
WE_REFUSED = "we_refused"  # this client did not accept the router's certificate
ROUTER_REFUSED = "router_refused"  # the router sent an alert about our certificate
SPEAKS_TLS = "speaks_tls"  # a plain tcp/ endpoint whose port answers a TLS handshake
NO_TLS = "no_tls"  # a tls/ endpoint whose port does not answer a TLS handshake
UNKNOWN = "unknown"  # nothing listens, unreachable, or a failure we cannot name


@dataclass(frozen=True)
class Probe:
    """What one TLS handshake showed: ``outcome`` (the constants above) and ``detail`` (the
    TLS library's reason, e.g. ``CERTIFICATE_EXPIRED`` or a verify message)."""

    outcome: str
    detail: str = ""


ROUTER_ALERTS = {
    "CERTIFICATE_REQUIRED": "this client presented no certificate",
    "CERTIFICATE_EXPIRED": "this client's certificate has expired",
    "DECRYPT_ERROR": "this client's certificate was not issued by the drone's CA",
    "BAD_CERTIFICATE": "this client's certificate was not issued by the drone's CA",
    "UNKNOWN_CA": "this client's certificate was not issued by the drone's CA",
    "CERTIFICATE_REVOKED": "this client's certificate was revoked",
    "UNSUPPORTED_CERTIFICATE": "this client's certificate is not one for TLS clients",
}
"""The router's TLS alert (as OpenSSL names it) -> what it says about our certificate."""


def alert_meaning(reason: str) -> str:
    """What the router's alert ``reason`` (``TLSV13_ALERT_CERTIFICATE_REQUIRED`` ...) says."""
    for alert, meaning in ROUTER_ALERTS.items():
        if alert in reason:
            return meaning
    return f"TLS alert {reason}"


def client_sentence(endpoint: str, identity: str, found: Probe, *, ca: str = "") -> str | None:
    """The sentence for a session that did not open on ``endpoint``, from ``found`` (pure);
    None when the probe names no cause (the caller says what else it knows). ``ca``: the CA
    file this client trusts, for the sentence.
    """
    who = f"identity={identity!r}" if identity else "no identity given"
    where = f"TLS handshake with {endpoint}"
    if found.outcome == ROUTER_REFUSED:
        meaning = alert_meaning(found.detail)
        fix = (
            "ask for a new certificate (`dronewrapper keys issue`)"
            if "expired" in meaning or "revoked" in meaning
            else "use the certificate the drone's key store issued (`dronewrapper keys export`)"
        )
        if "no certificate" in meaning and not identity:
            fix = "pass identity=NAME (see `dronewrapper keys`)"
        return f"{where} refused by the router: {meaning} ({who}); {fix}"
    if found.outcome == WE_REFUSED:
        if not identity:
            return (
                f"{where} refused by this client: the router's certificate is not trusted "
                f"({found.detail}) because no identity was given; a tls/ router needs the "
                "project's certificates: pass identity=NAME (see `dronewrapper keys`)"
            )
        trusted = f"the CA in {ca}" if ca else "this identity's CA"
        return (
            f"{where} refused by this client: the router's certificate does not verify with "
            f"{trusted} ({found.detail}; {who}): this identity and the drone come from "
            "different key stores, or the address dialled is not one the drone's certificate "
            "names (`dronewrapper keys issue NAME --host ADDRESS`)"
        )
    if found.outcome == SPEAKS_TLS:
        address = endpoint.partition("/")[2]
        given = f"identity={identity!r}" if identity else "identity=NAME (`dronewrapper keys`)"
        return (
            f"the router at {endpoint} speaks TLS on that port: connect with tls/{address} "
            f"and {given}"
        )
    if found.outcome == NO_TLS:
        return (
            f"{endpoint} does not answer a TLS handshake within {PROBE_TIMEOUT_S:g} s: is that "
            "port the router's tls/ listener, not a plain tcp/ one?"
        )
    return None


def probe(
    host: str,
    port: int,
    *,
    tls: bool,
    ca: Path | None = None,
    cert: Path | None = None,
    key: Path | None = None,
    timeout: float = PROBE_TIMEOUT_S,
) -> Probe:
    """One TLS handshake with ``host:port`` as a Zenoh client does it (I/O, about a millisecond
    on a LAN; at most ``timeout`` s per step). ``tls``: the endpoint was a ``tls/`` one (else
    a ``tcp/`` one, asked only whether its port speaks TLS)."""
    ctx = ssl.SSLContext(ssl.PROTOCOL_TLS_CLIENT)
    if not tls:
        ctx.check_hostname = False
        ctx.verify_mode = ssl.CERT_NONE
    elif ca is not None:
        ctx.load_verify_locations(str(ca))
    else:
        ctx.load_default_certs()
    if tls and cert is not None and key is not None:
        ctx.load_cert_chain(str(cert), str(key))
    try:
        with (
            socket.create_connection((host, port), timeout=timeout) as raw,
            ctx.wrap_socket(raw, server_hostname=host) as link,
        ):
            if not tls:
                return Probe(SPEAKS_TLS)
            link.settimeout(timeout)
            with contextlib.suppress(TimeoutError):
                link.recv(1)  # TLS 1.3: the router's verdict on our certificate comes now
            return Probe(ACCEPTED)
    except ssl.SSLCertVerificationError as exc:
        return Probe(WE_REFUSED, str(exc.verify_message or exc.reason))
    except ssl.SSLError as exc:
        if not tls:  # a TLS alert from the port: it speaks TLS
            return Probe(SPEAKS_TLS, str(exc.reason))
        return Probe(ROUTER_REFUSED, str(exc.reason or exc))
    except TimeoutError:
        return Probe(NO_TLS if tls else UNKNOWN)
    except OSError:
        return Probe(UNKNOWN)


ROUTER_WARNINGS = (
    (
        "received corrupt message",
        "plain",
        "a client spoke plain tcp to this TLS listener (it must connect with tls/ and an identity)",
    ),
    (
        "fatal alert: UnknownCA",
        "untrusted",
        "a client refused this router's certificate: it has no copy of the project's CA (no "
        "identity, or another key store)",
    ),
    (
        "fatal alert: DecryptError",
        "other_ca",
        "a client refused this router's certificate: it trusts another CA (a certificate "
        "from another key store)",
    ),
    (
        "fatal alert: BadCertificate",
        "untrusted",
        "a client refused this router's certificate (another CA, or an address the "
        "certificate does not name: `dronewrapper keys issue NAME --host ADDRESS`)",
    ),
    (
        "certificate expired",
        "expired",
        "refused a client whose certificate has expired",
    ),
    (
        "peer sent no certificates",
        "no_certificate",
        "refused a client that presented no certificate",
    ),
    (
        "NoCertificatesPresented",
        "no_certificate",
        "refused a client that presented no certificate",
    ),
    (
        "invalid peer certificate",
        "bad_certificate",
        "refused a client whose certificate was not issued by the drone's CA",
    ),
)
"""(text in Zenoh's accept warning, cause, what it means), first match wins."""


def router_meaning(message: str) -> tuple[str, str]:
    """``(cause, sentence)`` for one of Zenoh's TLS accept warnings (``zenoh_link_tls``)."""
    for text, cause, meaning in ROUTER_WARNINGS:
        if text in message:
            return cause, f"rejected TLS handshake: {meaning}"
    detail = message.split(". Hint:", 1)[0]
    return "other", f"rejected TLS handshake: {detail}"


class RejectionLog:
    """Lets each cause's sentence through once per ``interval_s`` (s, on the caller's clock),
    with how many handshakes of that cause were rejected since it last spoke (pure)."""

    def __init__(self, interval_s: float = 30.0) -> None:
        self.interval_s = interval_s
        self._last: dict[str, float] = {}
        self._count: dict[str, int] = {}

    def note(self, cause: str, sentence: str, now: float) -> str | None:
        """The line to log for one rejection at ``now``, or None while its cause is quiet."""
        self._count[cause] = self._count.get(cause, 0) + 1
        last = self._last.get(cause)
        if last is not None and now - last < self.interval_s:
            return None
        count, self._count[cause] = self._count[cause], 0
        self._last[cause] = now
        if last is None:
            return f"{sentence} (further ones logged at most every {self.interval_s:g} s)"
        return f"{sentence} ({count} in the last {now - last:.0f} s)"


def explain(connect: list[str], identity: str, keys_dir: str = "") -> str | None:
    """Why no session opens on ``connect`` with ``identity``, when a TLS handshake says so
    (one :func:`probe` per ``tls/`` or ``tcp/`` endpoint, I/O), else None."""
    from dronewrapper.runtime.options import tcp_address
    from dronewrapper.security.identity import Identity

    files: Identity | None = None
    if identity:
        try:
            files = Identity.load(identity, keys_dir or None)
        except (OSError, ValueError):
            return None  # opening the session said what is missing already
    for endpoint in connect:
        address = tcp_address(endpoint)
        if address is None:
            continue
        tls = endpoint.startswith("tls/")
        found = probe(
            *address,
            tls=tls,
            ca=files.ca if files else None,
            cert=files.cert if files else None,
            key=files.key if files else None,
        )
        sentence = client_sentence(
            endpoint, files.name if files else "", found, ca=str(files.ca) if files else ""
        )
        if sentence is not None:
            return sentence
    return None
