"""Why a call got no reply, told the way a person can act on it (pure apart from reading the
local key store).

A call nobody answered has four causes, each with its own exception and sentence:

- the router's access control dropped it because the identity may only watch: CommandRefused,
  "not permitted for role observer";
- the router refused the identity itself (revoked, expired or not in the drone's key store): it
  sees nothing at all on the router, NotConnected, "this identity was refused (revoked or
  unknown)";
- no bridge runs for the drone: NotConnected;
- a bridge runs but did not answer in time (busy or stuck): Timeout.

The role and revocation come from the local key store's ``index.json`` when the identity was
issued there; elsewhere (a laptop holding only its own certificate) they are inferred from what
the router shows the identity.
"""

from __future__ import annotations

import contextlib
import datetime as dt
from pathlib import Path

from dronewrapper.errors import CommandRefused, DroneError, NotConnected, Timeout

BRIDGE_PREFIX = "bridge"  # as discovery.BRIDGE_PREFIX: a process starting so is a bridge
WATCH_ONLY_ROLES = ("observer",)
"""Roles whose commands the router's access control drops (see security/acl.py)."""


def seconds(value: float) -> str:
    """A duration for a message: 0.1 s steps from 1 s up, two digits below (``9.9939`` -> ``10``,
    ``0.25`` -> ``0.25``)."""
    if value >= 1.0:
        return f"{round(value, 1):g}"
    return f"{value:.2g}"


def identity_name(identity: str) -> str:
    """The name of an identity given as a key-store name or a path to ``NAME.crt``."""
    return Path(identity).stem if identity.endswith(".crt") else identity


def local_standing(identity: str, keys_dir: str | Path | None = None) -> tuple[str, bool] | None:
    """``(role, refused)`` of ``identity`` from the local key store, ``refused`` meaning revoked
    or expired; None when the store does not know it."""
    if not identity:
        return None
    from dronewrapper.security.keystore import KeyStore

    name = identity_name(identity)
    with contextlib.suppress(OSError, ValueError, TypeError):
        for entry in KeyStore(keys_dir).entries():
            if entry.name == name:
                refused = entry.revoked or entry.expired(dt.datetime.now(dt.timezone.utc))
                return entry.role, refused
    return None


def identity_facts(identity: str, connect: str) -> dict[str, object]:
    """What the diagnoses take about our identity: ``identity`` (only on a ``tls/`` router,
    the one kind with access control) and its local ``standing``."""
    identity = identity if connect.startswith("tls/") else ""
    return {"identity": identity, "standing": local_standing(identity)}


def refused_identity(identity: str, connect: str) -> str:
    """The sentence for an identity the router refused."""
    return (
        f"this identity was refused (revoked or unknown): the router at {connect} shows "
        f"{identity_name(identity)!r} nothing; ask for a valid certificate "
        "(`dronewrapper keys list` on the drone's key store)"
    )


def no_reply(
    what: str,
    key: str,
    timeout: float,
    *,
    ns: str,
    connect: str,
    alive_names: set[str],
    sees_telemetry: bool = True,
    identity: str = "",
    standing: tuple[str, bool] | None = None,
) -> DroneError:
    """The exception for call ``what`` on ``key`` unanswered after ``timeout`` s.

    Args:
        alive_names: the liveliness keys the router showed in namespace ``ns``.
        sees_telemetry: the drone's State ever arrived (a refused identity sees none).
        identity: our certificate (``tls/`` routers), "" on a plain link.
        standing: ``(role, refused)`` from :func:`local_standing`, None when unknown.
    """
    waited = f"no reply from {key} within {seconds(timeout)} s"
    bridge = any(
        name.split("/")[-1].startswith(BRIDGE_PREFIX) and name.startswith(f"{ns}/")
        for name in alive_names
    )
    role, refused = standing if standing is not None else ("", False)
    shown_nothing = not alive_names and not sees_telemetry
    if identity and (refused or (standing is None and shown_nothing)):
        return NotConnected(f"{what}: {refused_identity(identity, connect)}")
    if identity and role in WATCH_ONLY_ROLES:
        return CommandRefused(
            what,
            f"not permitted for role {role} (identity {identity_name(identity)!r}): the "
            "router's access control lets it watch, not command; connect with an operator's "
            "certificate",
        )
    if bridge:
        if identity and not role:
            return Timeout(
                f"{what}: {waited}: the bridge is alive; if {identity_name(identity)!r} is an "
                "observer, the router drops its commands (not permitted for role observer)"
            )
        return Timeout(f"{what}: {waited}")
    return NotConnected(f"{what}: {waited}: no bridge is running for drone {ns!r} on {connect}")
