"""Who sent the sample or query being handled, and when: the ``commander`` attachment.

The SDK attaches ``commander=NAME`` (UTF-8) to every setpoint and command it sends; a setpoint
also carries its send time, ``commander=NAME\nsent=SECONDS`` (the publisher's clock, Unix s),
which the bridges' late-setpoint rule reads (``dronewrapper_bridge_base.setpoint_delay``).
The runtime records both around each subscriber callback and service handler, so a handler can
ask :func:`current_commander` and :func:`current_sent_at` without changing its signature.
Handlers run on the thread that called them, so a thread-local is enough.

On a router with access control the attachment is only a claim. A process with a certificate
sends its commands and setpoints on its **bound key**, the registry key followed by
``@by/NAME`` (``drone/mavros/cmd/arming/@by/alice``), and the router lets a certificate put
and query only under its own common name (:mod:`dronewrapper.security.acl`). A handler's
commander is the bound name when the key carries one, whatever the attachment says; the
attachment names the commander only on a plain key, which on a secure router only the drone's
own local processes may use. ``@by`` is a verbatim chunk: ``**`` and ``*`` do not match it, so
subscribers of ``drone/**`` see no duplicate of a command.
"""

from __future__ import annotations

import contextlib
import math
import threading
from collections.abc import Iterator
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from dronewrapper.runtime.options import ZenohOptions

_PREFIX = b"commander="
_SENT = b"\nsent="
_MAX_NAME = 64
BY = "@by"
"""The chunk before a bound key's commander name (verbatim: wildcards never match it)."""
_local = threading.local()


def bound_key(key: str, name: str) -> str:
    """``key`` bound to commander ``name`` (``key/@by/name``); ``key`` itself when no name."""
    return f"{key}/{BY}/{name}" if name else key


def any_bound(keyexpr: str) -> str:
    """The key expression of ``keyexpr`` bound to any commander (``keyexpr/@by/*``)."""
    return f"{keyexpr}/{BY}/*"


def split_bound(key: str) -> tuple[str, str]:
    """``(registry key, bound name)`` of a key (name ``""`` when the key is not bound).

    >>> split_bound("drone/mavros/cmd/arming/@by/alice"), split_bound("drone/mavros/state")
    (('drone/mavros/cmd/arming', 'alice'), ('drone/mavros/state', ''))
    """
    base, sep, name = key.rpartition(f"/{BY}/")
    if not sep or not name or "/" in name:
        return key, ""
    return base, name


def commander_attachment(name: str, sent: float | None = None) -> bytes:
    """The attachment naming ``name`` as the commander; ``sent``: the publication's send time
    (Unix s on the publisher's clock), carried by every setpoint."""
    raw = _PREFIX + name.encode()[:_MAX_NAME]
    if sent is not None and math.isfinite(sent):
        raw += _SENT + f"{sent:.6f}".encode()
    return raw


def origin_of(attachment: Any, key: str = "") -> tuple[str, float | None]:
    """(commander, send time or None) of a Zenoh attachment (``("", None)`` when none or not
    ours; an attachment without a send time has None). A bound ``key`` names the commander,
    whatever the attachment claims."""
    name, sent = _origin(attachment)
    bound = split_bound(key)[1] if key else ""
    return (bound or name), sent


def _origin(attachment: Any) -> tuple[str, float | None]:
    if attachment is None:
        return "", None
    raw = attachment.to_bytes() if hasattr(attachment, "to_bytes") else bytes(attachment)
    if not raw.startswith(_PREFIX):
        return "", None
    body, sep, sent_text = raw[len(_PREFIX) :].rpartition(_SENT)
    if not sep:
        body = sent_text
    sent: float | None = None
    if sep:
        try:
            sent = float(sent_text)
        except ValueError:
            body, sent = raw[len(_PREFIX) :], None
        else:
            sent = sent if math.isfinite(sent) else None
    return body[:_MAX_NAME].decode("utf-8", "replace"), sent


def commander_of(attachment: Any) -> str:
    """The commander named by a Zenoh attachment (``""`` when none or not ours)."""
    return origin_of(attachment)[0]


def current_commander() -> str:
    """The commander of the sample or query handled on this thread (``""`` if none)."""
    return getattr(_local, "commander", "")


def current_sent_at() -> float | None:
    """The send time (Unix s, the publisher's clock) of the sample handled on this thread
    (None if it carried none)."""
    return getattr(_local, "sent", None)


_NOTHING_TO_RECORD = contextlib.nullcontext()


def handling(attachment: Any, key: str = "") -> contextlib.AbstractContextManager[None]:
    """Record the commander (``key``'s bound name, else ``attachment``'s) and the send time
    while a callback or handler runs on the sample or query of ``key``.

    Without an attachment, on a thread that records nothing already (most telemetry), there
    is nothing to record nor to restore: a shared no-op context is returned (the generator
    context costs about a microsecond per sample)."""
    if (
        attachment is None
        and current_commander() == ""
        and current_sent_at() is None
        and f"/{BY}/" not in key
    ):
        return _NOTHING_TO_RECORD
    return _recording(attachment, key)


@contextlib.contextmanager
def _recording(attachment: Any, key: str) -> Iterator[None]:
    previous = current_commander(), current_sent_at()
    _local.commander, _local.sent = origin_of(attachment, key)
    try:
        yield
    finally:
        _local.commander, _local.sent = previous


def bound_name(options: ZenohOptions) -> str:
    """The name a node with ``options`` binds its commands to: its certificate's common name
    (``""`` without an identity)."""
    if not options.identity:
        return ""
    from dronewrapper.security.identity import Identity

    return Identity.load(options.identity, options.keys_dir or None).subject().name
