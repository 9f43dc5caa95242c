"""Errors raised by the runtime's request/reply calls."""

from __future__ import annotations


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
    """Nobody answered: the serving process is not running or not reachable."""

    def __init__(self, message: str) -> None:
        super().__init__(message, code="unavailable")
