"""A key store made for a secure-graph test: its CA, one certificate per identity and role,
and the MAVLink signing key the graph's autopilot link uses."""

from __future__ import annotations

from pathlib import Path

from dronewrapper.security.keystore import KeyStore


def issued_store(root: Path, roles: dict[str, str]) -> KeyStore:
    """A key store at ``root`` with a CA, a certificate for each ``name: role`` and a MAVLink
    signing key."""
    store = KeyStore(root)
    store.init()
    for name, role in roles.items():
        store.issue(name, role)
    store.new_mavlink_key()
    return store
