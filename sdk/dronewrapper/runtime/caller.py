"""Who sent the sample or query being handled: the ``commander`` attachment.

The SDK attaches ``commander=NAME`` (UTF-8) to every setpoint and command it sends; the runtime
records it around each subscriber callback and service handler, so a handler can ask
:func:`current_commander` without changing its signature. Handlers run on the thread that
called them, so a thread-local is enough.
"""

from __future__ import annotations

import contextlib
import threading
from collections.abc import Iterator
from typing import Any

_PREFIX = b"commander="
_MAX_NAME = 64
_local = threading.local()


def commander_attachment(name: str) -> bytes:
    """The attachment naming ``name`` as the commander."""
    return _PREFIX + name.encode()[:_MAX_NAME]


def commander_of(attachment: Any) -> str:
    """The commander named by a Zenoh attachment (``""`` when none or not ours)."""
    if attachment is None:
        return ""
    raw = attachment.to_bytes() if hasattr(attachment, "to_bytes") else bytes(attachment)
    if not raw.startswith(_PREFIX):
        return ""
    return raw[len(_PREFIX) :][:_MAX_NAME].decode("utf-8", "replace")


def current_commander() -> str:
    """The commander of the sample or query handled on this thread (``""`` if none)."""
    return getattr(_local, "commander", "")


@contextlib.contextmanager
def handling(attachment: Any) -> Iterator[None]:
    """Record ``attachment``'s commander while a callback or handler runs."""
    previous = current_commander()
    _local.commander = commander_of(attachment)
    try:
        yield
    finally:
        _local.commander = previous
