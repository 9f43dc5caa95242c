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

The role comes from the identity's own certificate (``dronewrapper keys issue`` writes it in
the subject), so a laptop holding only its three files knows it; an observer's command is then
refused at once (:func:`role_refusal`), before it is sent. Revocation comes from the local key
store's ``index.json`` when the identity was issued there; elsewhere it is inferred from what
the router shows the identity. Every duration in a sentence is the one actually waited.
"""

from __future__ import annotations

import contextlib
import datetime as dt
from pathlib import Path
from typing import TypedDict

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


def certificate_role(identity: str, keys_dir: str | Path | None = None) -> str:
    """The role ``identity``'s own certificate names (``""`` when it names none or cannot be
    read)."""
    if not identity:
        return ""
    from dronewrapper.security.identity import Identity

    with contextlib.suppress(OSError, ValueError, TypeError):
        return Identity.load(identity, keys_dir).subject().role
    return ""


def local_standing(identity: str, keys_dir: str | Path | None = None) -> tuple[str, bool] | None:
    """``(role, refused)`` of ``identity``: the role its certificate names (else the local key
    store's), ``refused`` meaning revoked or expired in the local key store; None when neither
    knows it."""
    if not identity:
        return None
    from dronewrapper.security.keystore import KeyStore

    name = identity_name(identity)
    role = certificate_role(identity, keys_dir)
    with contextlib.suppress(OSError, ValueError, TypeError):
        for entry in KeyStore(keys_dir).entries():
            if entry.name == name:
                refused = entry.revoked or entry.expired(dt.datetime.now(dt.timezone.utc))
                return role or entry.role, refused
    return (role, False) if role else None


def role_refusal(role: str, identity: str) -> str:
    """Why a command of ``identity``, whose certificate's role is ``role``, is not sent."""
    return (
        f"not permitted for role {role} (identity {identity_name(identity)!r}, as its "
        "certificate says): the router's access control lets it watch, not command; connect "
        "with an operator's certificate"
    )


def forbidden(identity: str, connect: str, keys_dir: str | Path | None = None) -> str:
    """The reason every command of ``identity`` on router ``connect`` would be dropped by the
    router, known before sending (a watch-only role in its certificate), else ``""``."""
    if not identity or not connect.startswith("tls/"):
        return ""
    role = certificate_role(identity, keys_dir)
    return f"{role_refusal(role, identity)} (not sent)" if role in WATCH_ONLY_ROLES else ""


def node_forbidden(node: object) -> str:
    """:func:`forbidden` for a node opened elsewhere (a ``Fleet``'s, an app's own): its
    identity and the first ``tls/`` router it connects to; ``""`` for a node without options
    (the fake bus) or identity."""
    options = getattr(node, "options", None)
    identity = getattr(options, "identity", "")
    if options is None or not identity:
        return ""
    tls = next((ep for ep in options.connect if ep.startswith("tls/")), "")
    return forbidden(identity, tls, options.keys_dir or None)


class IdentityFacts(TypedDict):
    """Our identity as the diagnoses take it (keywords of :func:`no_reply` and others)."""

    identity: str
    standing: tuple[str, bool] | None


def identity_facts(identity: str, connect: str) -> IdentityFacts:
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
    """The exception for call ``what`` on ``key`` unanswered after ``timeout`` s (the time
    actually waited).

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
        return CommandRefused(what, role_refusal(role, identity))
    if bridge:
        if identity and not role:
            return Timeout(
                f"{what}: {waited}: the bridge is alive; the certificate of "
                f"{identity_name(identity)!r} names no role: if it is an observer's, the "
                "router drops its commands"
            )
        return Timeout(f"{what}: {waited}")
    return NotConnected(f"{what}: {waited}: no bridge is running for drone {ns!r} on {connect}")
