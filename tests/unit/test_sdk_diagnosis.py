"""A call nobody answered, diagnosed: a watch-only role, a refused identity, no bridge, or a
silent bridge; and durations printed as a person reads them (pure)."""

from __future__ import annotations

import types

import pytest

from dronewrapper.diagnosis import (
    forbidden,
    identity_facts,
    local_standing,
    no_reply,
    node_forbidden,
    role_refusal,
    seconds,
)
from dronewrapper.discovery import connection_problem
from dronewrapper.errors import CommandRefused, NotConnected, Timeout
from dronewrapper.runtime.options import ZenohOptions
from dronewrapper.security.keystore import KeyStore

TLS = "tls/192.168.1.10:7448"
ALIVE = {"drone/alive/bridge_mavlink", "drone/alive/sim"}
KEY = "drone/mavros/cmd/arming"


def ask(**kwargs):
    return no_reply("arming", KEY, 9.9939, ns="drone", connect=TLS, alive_names=ALIVE, **kwargs)


@pytest.mark.parametrize(
    ("value", "text"), [(9.9939, "10"), (10.0, "10"), (2.46, "2.5"), (0.25, "0.25"), (0.04, "0.04")]
)
def test_durations_read_as_a_person_writes_them(value, text):
    assert seconds(value) == text


def test_an_observers_command_is_not_permitted_for_its_role():
    error = ask(identity="olga", standing=("observer", False))
    assert isinstance(error, CommandRefused)
    assert "not permitted for role observer" in str(error) and "'olga'" in str(error)


def test_an_identity_whose_certificate_names_no_role_is_told_what_the_silence_may_mean():
    error = ask(identity="olga", standing=None)
    assert isinstance(error, Timeout)
    assert "within 10 s" in str(error) and "9.99" not in str(error)
    assert "names no role: if it is an observer's, the router drops its commands" in str(error)


def test_the_time_in_a_sentence_is_the_time_waited():
    """A call whose query no server took ends after 2 s: it says 2 s, not its 10 s timeout."""
    error = no_reply("arming", KEY, 2.0, ns="drone", connect=TLS, alive_names=ALIVE)
    assert "within 2 s" in str(error) and "10 s" not in str(error)


def test_a_revoked_identity_is_told_it_was_refused_not_that_no_bridge_runs():
    error = ask(identity="rex", standing=("operator", True))
    assert isinstance(error, NotConnected)
    assert "this identity was refused (revoked or unknown)" in str(error)
    where = {"ns": "drone", "connect": TLS, "alive_names": set(), "identity": "x"}
    nothing = no_reply("arming", KEY, 10, sees_telemetry=False, **where)
    assert "this identity was refused (revoked or unknown)" in str(nothing)
    assert "Start one" not in str(nothing)
    watching = no_reply("arming", KEY, 10, sees_telemetry=True, **where)  # it sees the drone
    assert "refused (revoked" not in str(watching)


def test_without_identity_the_bridge_decides_between_timeout_and_not_connected():
    plain = {"ns": "drone", "connect": "tcp/127.0.0.1:7447"}
    assert str(no_reply("arming", KEY, 10, alive_names=ALIVE, **plain)) == (
        f"arming: no reply from {KEY} within 10 s"
    )
    gone = no_reply("arming", KEY, 10, alive_names={"drone/alive/sim"}, **plain)
    assert isinstance(gone, NotConnected) and "no bridge is running for drone 'drone'" in str(gone)


def test_connecting_with_a_refused_identity_says_so():
    facts = {"linked": True, "state_connected": None, "state_age": 99.0, "fresh_s": 1.5}
    text = connection_problem("drone", TLS, alive_keys=set(), waited=5, identity="rex", **facts)
    assert text.startswith("this identity was refused (revoked or unknown)")
    plain = connection_problem("drone", TLS, alive_keys=set(), waited=5, **facts)
    assert plain.startswith("no bridge for drone 'drone'")


def test_the_local_key_store_knows_role_and_revocation(tmp_path, monkeypatch):
    store = KeyStore(tmp_path / "keys")
    store.init()
    store.issue("olga", "observer")
    store.issue("rex", "operator")
    store.revoke("rex")
    monkeypatch.setenv("DRONEWRAPPER_KEYS", str(store.root))
    assert local_standing("olga") == ("observer", False)
    assert local_standing("rex") == ("operator", True)
    assert local_standing(str(store.cert("olga"))) == ("observer", False)
    assert local_standing("nobody") is None and local_standing("") is None
    assert identity_facts("olga", "tcp/127.0.0.1:7447") == {"identity": "", "standing": None}
    assert identity_facts("olga", TLS)["standing"] == ("observer", False)


def test_the_role_comes_from_the_certificate_without_the_index(tmp_path, monkeypatch):
    """A laptop holds ca.crt, NAME.crt and NAME.key only: the certificate says the role, so an
    observer's command is refused before it is sent, over TLS; on a plain link, nothing."""
    store = KeyStore(tmp_path / "keys")
    store.init()
    store.issue("olga", "observer")
    store.issue("alice", "operator")
    laptop = tmp_path / "laptop"
    store.export("olga", laptop)
    store.export("alice", laptop)
    assert not (laptop / "index.json").exists()
    monkeypatch.setenv("DRONEWRAPPER_KEYS", str(laptop))
    assert local_standing("olga") == ("observer", False)
    assert forbidden("olga", TLS) == role_refusal("observer", "olga") + " (not sent)"
    assert "not permitted for role observer (identity 'olga', as its certificate says)" in (
        forbidden("olga", TLS)
    )
    assert forbidden("alice", TLS) == "" and forbidden("olga", "tcp/127.0.0.1:7447") == ""


def test_a_shared_nodes_identity_is_judged_the_same(tmp_path, monkeypatch):
    """A Fleet's or an app's own node: its options name the identity and the router, so an
    observer's command through it is refused before sending too."""
    store = KeyStore(tmp_path / "keys")
    store.init()
    store.issue("olga", "observer")
    monkeypatch.setenv("DRONEWRAPPER_KEYS", str(store.root))

    def node(identity, *connect):
        options = ZenohOptions(connect=list(connect), identity=identity)
        return types.SimpleNamespace(options=options)

    assert node_forbidden(node("olga", "tcp/127.0.0.1:7447", TLS)) == forbidden("olga", TLS)
    assert "not permitted for role observer" in node_forbidden(node("olga", TLS))
    assert node_forbidden(node("olga", "tcp/127.0.0.1:7447")) == ""
    assert node_forbidden(node("", TLS)) == "" and node_forbidden(object()) == ""
