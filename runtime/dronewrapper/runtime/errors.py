"""Errors raised by the runtime's request/reply calls."""

from __future__ import annotations

import re


class ServiceError(RuntimeError):
    """A service answered with an error reply, or should answer with one.

    Raise it in a service handler to send an error reply; a caller receives it when the server
    replied with an error. ``code`` is one of ``bad_request``, ``refused``, ``timeout``,
    ``unavailable``, ``internal``.
    """

    def __init__(self, message: str, code: str = "refused") -> None:
        super().__init__(message)
        self.message = message
        self.code = code


class ServiceUnavailable(ServiceError):
    """Nobody answered: the serving process is not running or not reachable.

    Attributes:
        waited: seconds the call actually waited (less than its timeout when no server took
            the query at all), None when unknown.
    """

    def __init__(self, message: str, waited: float | None = None) -> None:
        super().__init__(message, code="unavailable")
        self.waited = waited


class ServiceTimeout(ServiceUnavailable):
    """Zenoh ended the query at its timeout with no reply: a server that got the request may be
    busy or stuck (the request may still take effect), or the query reached none at the last
    moment. A kind of :class:`ServiceUnavailable`, never a refusal."""

    def __init__(self, message: str, waited: float | None = None) -> None:
        super().__init__(message, waited)
        self.code = "timeout"


_RUST_SOURCE = re.compile(r"\s*\bat /\S+?\.rs:\d+\.?")
_BRACKETED_EMPTY = re.compile(r"\[\s*\]")


def zenoh_error_text(exc: BaseException) -> str:
    """A Zenoh error as one readable line: no Rust source paths, no line breaks.

    >>> zenoh_error_text(ValueError("Unable to connect!  at /root/.cargo/x/orchestrator.rs:447."))
    'Unable to connect!'
    """
    text = _BRACKETED_EMPTY.sub("", _RUST_SOURCE.sub("", str(exc)))
    return " ".join(text.split()).rstrip(" .:")
