"""A refused TLS handshake named from the side that knows: the client's sentence per probe
outcome, the router's meaning per Zenoh warning, once per cause and interval (pure)."""

from __future__ import annotations

import logging

import pytest

from dronewrapper.security.handshake import (
    NO_TLS,
    ROUTER_REFUSED,
    SPEAKS_TLS,
    UNKNOWN,
    WE_REFUSED,
    Probe,
    RejectionLog,
    client_sentence,
    router_meaning,
)
from dronewrapper.zenoh_log import Relay, parse

TLS = "tls/10.0.0.5:7448"


@pytest.mark.parametrize(
    ("identity", "probe", "says"),
    [
        ("old", Probe(ROUTER_REFUSED, "SSLV3_ALERT_CERTIFICATE_EXPIRED"),
         "refused by the router: this client's certificate has expired (identity='old')"),
        ("mallory", Probe(ROUTER_REFUSED, "TLSV1_ALERT_DECRYPT_ERROR"),
         "refused by the router: this client's certificate was not issued by the drone's CA "
         "(identity='mallory')"),
        ("", Probe(ROUTER_REFUSED, "TLSV13_ALERT_CERTIFICATE_REQUIRED"),
         "refused by the router: this client presented no certificate (no identity given); "
         "pass identity=NAME"),
        ("", Probe(WE_REFUSED, "unable to get local issuer certificate"),
         "refused by this client: the router's certificate is not trusted (unable to get local "
         "issuer certificate) because no identity was given"),
        ("mallory", Probe(WE_REFUSED, "certificate signature failure"),
         "refused by this client: the router's certificate does not verify with the CA in "
         "/k/ca.crt (certificate signature failure; identity='mallory')"),
    ],
)  # fmt: skip
def test_the_client_is_told_which_side_refused_and_why(identity, probe, says):
    sentence = client_sentence(TLS, identity, probe, ca="/k/ca.crt" if identity else "")
    assert sentence is not None and says in sentence, sentence
    assert sentence.startswith(f"TLS handshake with {TLS} refused by ")
    assert "may not be running" not in sentence


def test_plain_tcp_on_a_tls_port_and_tls_on_a_plain_port():
    plain = client_sentence("tcp/10.0.0.5:7448", "alice", Probe(SPEAKS_TLS))
    assert plain == (
        "the router at tcp/10.0.0.5:7448 speaks TLS on that port: connect with "
        "tls/10.0.0.5:7448 and identity='alice'"
    )
    silent = client_sentence(TLS, "alice", Probe(NO_TLS))
    assert silent is not None and "does not answer a TLS handshake" in silent
    assert client_sentence(TLS, "alice", Probe(UNKNOWN)) is None  # the caller says the rest


HINT = ". Hint: increase the system open file limit."


@pytest.mark.parametrize(
    ("warning", "cause", "meaning"),
    [
        ("received corrupt message of type InvalidContentType", "plain",
         "a client spoke plain tcp to this TLS listener"),
        ("received fatal alert: UnknownCA", "untrusted",
         "a client refused this router's certificate: it has no copy of the project's CA"),
        ("received fatal alert: DecryptError", "other_ca", "it trusts another CA"),
        ("invalid peer certificate: certificate expired: verification time 1795819624 (UNIX)",
         "expired", "refused a client whose certificate has expired"),
        ("peer sent no certificates", "no_certificate",
         "refused a client that presented no certificate"),
        ("invalid peer certificate: BadSignature", "bad_certificate",
         "certificate was not issued by the drone's CA"),
    ],
)  # fmt: skip
def test_the_router_says_what_a_rejected_handshake_means(warning, cause, meaning):
    found, sentence = router_meaning(warning + HINT)
    assert found == cause and meaning in sentence
    assert sentence.startswith("rejected TLS handshake: ") and "open file limit" not in sentence


def test_rejections_are_logged_once_per_cause_and_interval_with_a_count():
    log = RejectionLog(interval_s=30.0)
    first = log.note("expired", "rejected TLS handshake: x", 0.0)
    assert first == "rejected TLS handshake: x (further ones logged at most every 30 s)"
    assert all(log.note("expired", "x", t * 0.2) is None for t in range(1, 150))  # 0.2 s retries
    assert log.note("plain", "rejected TLS handshake: y", 1.0) is not None  # another cause
    again = log.note("expired", "rejected TLS handshake: x", 30.0)
    assert again == "rejected TLS handshake: x (150 in the last 30 s)"


def test_zenohs_log_lines_are_relayed_with_their_meaning():
    line = (
        "\x1b[2m2026-11-27T22:46:22.927398Z\x1b[0m \x1b[33m WARN\x1b[0m acc-0 ThreadId(04) "
        "\x1b[2mzenoh_link_tls::unicast\x1b[0m\x1b[2m:\x1b[0m received fatal alert: "
        "DecryptError. Hint: increase the system open file limit.\n"
    )
    parsed = parse(line)
    assert parsed is not None and parsed.level == logging.WARNING
    assert parsed.target == "zenoh_link_tls::unicast"
    relay = Relay(interval_s=10.0)
    level, text = relay.handle(line, 0.0)
    assert level == logging.WARNING and "it trusts another CA" in text
    assert relay.handle(line, 0.2) is None and relay.handle(line, 9.9) is None
    assert "(3 in the last 10 s)" in relay.handle(line, 10.0)[1]  # 0.2, 9.9 and 10
    other = "2026-11-27T22:46:22Z ERROR zenoh::net::runtime: something broke\n"
    assert relay.handle(other, 0.0) == (logging.ERROR, "zenoh::net::runtime: something broke")
    assert relay.handle("a child's own line\n", 0.0) == (None, "a child's own line\n")
