"""The key store: a CA, certificates per role, 0600 files, revocation, the MAVLink key."""

from __future__ import annotations

import datetime as dt
import stat

import pytest
from cryptography import x509
from cryptography.x509.oid import NameOID

from dronewrapper.cli import main as cli_main
from dronewrapper.security.identity import Identity, Subject
from dronewrapper.security.keystore import KeyStore, KeyStoreError, read_mavlink_key


@pytest.fixture
def store(tmp_path):
    store = KeyStore(tmp_path / "keys")
    store.init()
    return store


def _mode(path):
    return stat.S_IMODE(path.stat().st_mode)


def test_every_file_is_private(store):
    store.issue("drone1", "drone", hosts=["10.0.0.5", "drone1.local"])
    store.issue("alice", "operator")
    store.new_mavlink_key()
    assert _mode(store.root) == 0o700
    files = sorted(store.root.iterdir())
    assert {p.name for p in files} >= {"ca.key", "ca.crt", "drone1.key", "alice.crt"}
    assert all(_mode(p) == 0o600 for p in files), {p.name: oct(_mode(p)) for p in files}


def test_certificate_names_the_identity_and_chains_to_the_ca(store):
    store.issue("drone1", "drone", hosts=["10.0.0.5", "drone1.local"])
    cert = x509.load_pem_x509_certificate(store.cert("drone1").read_bytes())
    ca = x509.load_pem_x509_certificate(store.ca_cert.read_bytes())
    assert cert.subject.get_attributes_for_oid(NameOID.COMMON_NAME)[0].value == "drone1"
    assert cert.issuer == ca.subject
    cert.verify_directly_issued_by(ca)
    sans = cert.extensions.get_extension_for_class(x509.SubjectAlternativeName).value
    assert "drone1.local" in sans.get_values_for_type(x509.DNSName)
    assert [str(ip) for ip in sans.get_values_for_type(x509.IPAddress)] == [
        "127.0.0.1",
        "10.0.0.5",
    ]


def test_the_certificate_says_its_role(store):
    """The role is in the subject (organizational unit): a laptop reads its own role from its
    certificate, without the drone's index.json. An old certificate without one reads ""."""
    for name, role in (("drone1", "drone"), ("alice", "operator"), ("olga", "observer")):
        store.issue(name, role)
        assert Identity.load(name, store.root).subject() == Subject(name, role)
    cert = x509.load_pem_x509_certificate(store.cert("olga").read_bytes())
    assert cert.subject.get_attributes_for_oid(NameOID.ORGANIZATIONAL_UNIT_NAME)[0].value == (
        "observer"
    )


def test_roles_exclude_revoked_and_expired(store):
    store.issue("drone1", "drone")
    store.issue("alice", "operator")
    store.issue("bob", "observer")
    past = dt.datetime.now(dt.timezone.utc) - dt.timedelta(days=3)
    store.issue("old", "operator", days=1, now=past)
    store.revoke("bob")
    roles = store.names_by_role()
    assert roles == {"drone": ["drone1"], "operator": ["alice"], "observer": [], "relay": []}
    with pytest.raises(KeyStoreError, match="revoked"):
        store.issue("bob", "observer")


def test_refusals_say_why(store, tmp_path):
    with pytest.raises(KeyStoreError, match="exists"):
        store.init()
    with pytest.raises(KeyStoreError, match="role"):
        store.issue("x", "admin")
    with pytest.raises(KeyStoreError, match="name"):
        store.issue("../evil", "operator")
    with pytest.raises(KeyStoreError, match="keys init"):
        KeyStore(tmp_path / "empty").issue("a", "operator")
    with pytest.raises(KeyStoreError, match="no certificate"):
        store.revoke("nobody")


def test_a_ca_key_of_another_kind_is_refused_by_name(store):
    from cryptography.hazmat.primitives import serialization
    from cryptography.hazmat.primitives.asymmetric import ed25519

    other = ed25519.Ed25519PrivateKey.generate().private_bytes(
        serialization.Encoding.PEM,
        serialization.PrivateFormat.PKCS8,
        serialization.NoEncryption(),
    )
    store.ca_key.write_bytes(other)
    with pytest.raises(KeyStoreError, match="not an elliptic-curve private key"):
        store.issue("drone1", "drone")


def test_mavlink_key_is_32_bytes(store):
    key = store.new_mavlink_key()
    assert len(key) == 32 and read_mavlink_key(store.mavlink_key) == key
    with pytest.raises(KeyStoreError, match="exists"):
        store.new_mavlink_key()
    assert store.new_mavlink_key(force=True) != key


def test_identity_resolves_by_name_or_path(store):
    store.issue("alice", "operator")
    by_name = Identity.load("alice", store.root)
    assert Identity.load(str(store.cert("alice"))) == by_name
    tls = by_name.tls_config()
    assert tls["enable_mtls"] and tls["root_ca_certificate"] == str(store.ca_cert)
    with pytest.raises(FileNotFoundError, match="bob"):
        Identity.load("bob", store.root)


def test_export_copies_what_a_laptop_needs_and_never_the_ca_key(store, tmp_path):
    store.issue("alice", "operator")
    out = tmp_path / "laptop"
    written = store.export("alice", out)
    assert sorted(p.name for p in written) == ["alice.crt", "alice.key", "ca.crt"]
    assert not (out / "ca.key").exists()
    assert all(_mode(p) == 0o600 for p in written) and _mode(out) == 0o700
    assert Identity.load("alice", out).cert == out / "alice.crt"
    store.revoke("alice")
    with pytest.raises(KeyStoreError, match="revoked"):
        store.export("alice", tmp_path / "again")


def test_export_for_a_router_carries_the_roles_its_access_control_grants(store, tmp_path):
    store.issue("link", "relay", hosts=["10.0.0.7"])
    store.issue("field", "drone")
    out = tmp_path / "relay_box"
    written = store.export("link", out, router=True)
    assert sorted(p.name for p in written) == ["ca.crt", "index.json", "link.crt", "link.key"]
    assert all(_mode(p) == 0o600 for p in written) and not (out / "ca.key").exists()
    roles = KeyStore(out).names_by_role()
    assert roles["relay"] == ["link"] and roles["drone"] == ["field"]
    assert KeyStore(tmp_path / "laptop").names_by_role()["drone"] == []  # without: nobody


def test_cli_round_trip(tmp_path, capsys):
    keys = str(tmp_path / "k")
    assert cli_main(["keys", "--keys", keys, "init"]) == 0
    assert cli_main(["keys", "--keys", keys, "issue", "alice", "--role", "operator"]) == 0
    assert cli_main(["keys", "--keys", keys, "revoke", "alice"]) == 0
    assert cli_main(["keys", "--keys", keys, "mavlink"]) == 0
    assert cli_main(["keys", "--keys", keys, "list"]) == 0
    assert "alice" in capsys.readouterr().out.splitlines()[-1]
    assert cli_main(["keys", "--keys", keys, "issue", "alice", "--role", "operator"]) == 1
    assert "revoked" in capsys.readouterr().err
