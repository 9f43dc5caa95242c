"""Who may command the station: loopback, the one-time token, observers, browser attacks."""

from __future__ import annotations

import pytest

from dronewrapper_ground_station.access import (
    OBSERVER,
    OPERATOR,
    Access,
    is_loopback,
    new_token,
    split_host,
)
from dronewrapper_ground_station.config import Config
from dronewrapper_ground_station.node import operator_token, page_url

TOKEN = "t" * 22


@pytest.mark.parametrize("host", ["127.0.0.1", "127.0.0.2", "::1", "[::1]", "localhost"])
def test_loopback_addresses(host: str) -> None:
    assert is_loopback(host)


@pytest.mark.parametrize("host", ["192.168.1.10", "0.0.0.0", "example.com", "", "10.0.0.1"])
def test_other_addresses_are_not_loopback(host: str) -> None:
    assert not is_loopback(host)


@pytest.mark.parametrize(
    ("header", "host"),
    [("127.0.0.1:8080", "127.0.0.1"), ("[::1]:8080", "::1"), ("localhost", "localhost")],
)
def test_host_header_names_the_host(header: str, host: str) -> None:
    assert split_host(header) == host


def test_loopback_page_is_an_operator_without_token() -> None:
    assert Access().role("127.0.0.1", "127.0.0.1:8080", "") == OPERATOR
    assert Access(TOKEN).role("127.0.0.1", "localhost:8080", "") == OPERATOR


def test_remote_page_is_an_observer_without_the_token() -> None:
    access = Access(TOKEN)
    assert access.role("192.168.1.20", "192.168.1.10:8080", "") == OBSERVER
    assert access.role("192.168.1.20", "192.168.1.10:8080", "wrong-token-wrong") == OBSERVER
    assert access.role("192.168.1.20", "192.168.1.10:8080", TOKEN) == OPERATOR


def test_any_presented_token_is_compared_safely() -> None:
    """Non-ASCII text must not crash the comparison (hmac refuses non-ASCII str)."""
    assert Access(TOKEN).role("192.168.1.20", "h:1", "é" * 22) == OBSERVER


def test_no_token_configured_means_no_remote_operator() -> None:
    assert Access("").role("192.168.1.20", "192.168.1.10:8080", "") == OBSERVER


def test_dns_rebinding_gets_no_operator() -> None:
    """A page of evil.example that resolved to 127.0.0.1 reaches us from loopback, but asks
    for its own host name."""
    assert Access().role("127.0.0.1", "evil.example:8080", "") == OBSERVER


@pytest.mark.parametrize(
    ("origin", "ok"),
    [
        (None, True),
        ("http://127.0.0.1:8080", True),
        ("http://evil.example", False),
        ("http://127.0.0.1:9999", False),
        ("null", False),
        ("file://", False),
    ],
)
def test_same_origin(origin: str | None, ok: bool) -> None:
    assert Access.same_origin(origin, "127.0.0.1:8080") is ok


def test_tokens_are_fresh_and_long() -> None:
    a, b = new_token(), new_token()
    assert a != b and len(a) >= 20


def test_token_only_beyond_loopback() -> None:
    assert operator_token(Config()) == ""
    assert len(operator_token(Config(host="0.0.0.0"))) >= 20
    assert operator_token(Config(host="0.0.0.0")) != operator_token(Config(host="0.0.0.0"))
    assert operator_token(Config(host="0.0.0.0", token=TOKEN)) == TOKEN


def test_page_url() -> None:
    assert page_url("127.0.0.1", 8080, "") == "http://127.0.0.1:8080/"
    assert page_url("0.0.0.0", 8080, "abc") == "http://HOST:8080/?token=abc"
    assert page_url("::1", 80, "") == "http://[::1]:80/"
