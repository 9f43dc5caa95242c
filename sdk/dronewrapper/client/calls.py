"""A drone client's service calls: each carries our commander name; blocking or pending.

:meth:`Calls.ask` is a request and its reply, on the caller's thread. :meth:`Calls.call`
returns a :class:`Pending` at once, which a loop polls (``done(now)``, then ``result(now)``):
the request waits on a worker thread owned here, or is answered inline (the fake bus, whose
services answer synchronously, and the SDK's blocking calls, which wait anyway). A certificate
whose role may not command has every call refused here, unsent (the router would drop it).
Time: the node's monotonic clock (s).
"""

from __future__ import annotations

import math
from concurrent.futures import Future, ThreadPoolExecutor
from typing import Any, Generic, TypeVar

from dronewrapper.msgs.registry import Service
from dronewrapper.runtime.caller import commander_attachment
from dronewrapper.runtime.contract import NodeApi
from dronewrapper.runtime.errors import ServiceError

Req = TypeVar("Req")
Rep = TypeVar("Rep")

CALL_WORKERS = 4
"""Calls under way at once: a call left waiting for a silent server never holds up the next
one (a landing after a take-off step that got no reply)."""


class Pending(Generic[Rep]):
    """A service call under way: poll :meth:`done`, then read :meth:`result`.

    ``deadline`` is on the loop's clock (s): past it the call counts as unanswered even if a
    worker still waits for the reply (whose late answer is then ignored).
    """

    def __init__(self, what: str, future: Future[Rep], deadline: float, timeout: float) -> None:
        self.what = what
        self.deadline = deadline
        self.timeout = timeout
        self._future = future

    def done(self, now: float) -> bool:
        """True once the reply (or an error) is in, or the deadline has passed."""
        return self._future.done() or now >= self.deadline

    def result(self, now: float) -> Rep:
        """The reply.

        Raises:
            ServiceError: the server refused the request (its message says why).
            ServiceUnavailable: nobody answered within the call's timeout.
            TimeoutError: the deadline passed before the reply came.
            RuntimeError: asked before :meth:`done`.
        """
        if self._future.done():
            return self._future.result()
        if now >= self.deadline:
            self._future.cancel()
            raise TimeoutError(f"{self.what}: no reply within {self.timeout:g} s")
        raise RuntimeError(f"{self.what}: the reply is still pending")


class Calls:
    """The service calls of one drone (see the module doc).

    Args:
        node: the node the client stands on; ``ns``: the drone's namespace.
        commander: our name on the command lease (the ``commander`` attachment).
        inline: answer :meth:`call` on the caller's thread instead of a worker's.
        forbidden: why our certificate's role may not command ("" when it may).
    """

    def __init__(
        self, node: NodeApi, ns: str, commander: str, *, inline: bool, forbidden: str = ""
    ) -> None:
        self.ns = ns
        self.forbidden = forbidden
        self._node = node
        self._attachment = commander_attachment(commander)
        self._pool = (
            None
            if inline
            else ThreadPoolExecutor(
                max_workers=CALL_WORKERS, thread_name_prefix=f"{node.name}-calls"
            )
        )

    def ask(self, service: Service[Any, Rep], request: Any, timeout: float) -> Rep:
        """One request/reply; raises the runtime's ServiceError / ServiceUnavailable, and
        ServiceError (code ``forbidden``) at once, unsent, when our role may not command."""
        if self.forbidden:
            raise ServiceError(self.forbidden, "forbidden")
        return self._node.call(
            service, request, ns=self.ns, timeout=timeout, attachment=self._attachment
        )

    def call(
        self,
        service: Service[Req, Rep],
        request: Req,
        now: float,
        *,
        timeout: float,
        what: str = "",
    ) -> Pending[Rep]:
        """Send ``request`` to ``service`` in this namespace; returns at once.

        ``timeout`` (s) bounds the wait for the reply, on the loop's clock and on the wire.
        """
        if not (math.isfinite(timeout) and timeout > 0):
            raise ValueError(f"timeout must be > 0 s, got {timeout!r}")
        what = what or service.key(self.ns)

        def ask() -> Rep:
            return self.ask(service, request, timeout)

        if self._pool is None:
            future: Future[Rep] = Future()
            try:
                future.set_result(ask())
            except Exception as exc:
                future.set_exception(exc)
        else:
            future = self._pool.submit(ask)
        return Pending(what, future, now + timeout, timeout)

    def close(self) -> None:
        """Drop calls not started yet (a call under way ends by its timeout, or when the
        node's session closes)."""
        if self._pool is not None:
            self._pool.shutdown(wait=False, cancel_futures=True)
