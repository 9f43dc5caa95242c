"""The bridge's refusals addressed to us: what a client keeps, prints and calls back.

A bridge publishes each setpoint it refuses and each breach that overrides its commander on
``{ns}/dronewrapper/refusal`` (:mod:`dronewrapper.msgs.refusal`), naming the commander. A
:class:`RefusalInbox` takes those naming ``commander`` (and those naming nobody: a breach while
nobody held the lease or streamed), the moment they arrive, on the subscription's thread:

- keeps the last :data:`KEEP` (``recent``, newest last) and counts them (``received``);
- prints one warning line per refusal stream (``[dronewrapper] drone: setpoint refused
  (envelope, max_altitude): ...``), again only after :data:`WARN_AGAIN_S` of the same;
- calls every listener with the :class:`~dronewrapper.msgs.refusal.Refusal` (an exception in
  one is logged, never lost into the bus).

Time is the node's clock (``received_at``: monotonic s of the newest arrival).
"""

from __future__ import annotations

import collections
import logging
import threading
from collections.abc import Callable

from dronewrapper.msgs.refusal import Refusal
from dronewrapper.runtime.clock import Clock

log = logging.getLogger("dronewrapper")

KEEP = 20
"""How many refusals ``recent`` keeps."""
WARN_AGAIN_S = 5.0
"""A refusal stream (same kind, input and limit) is warned about again after this long (s)."""


class RefusalInbox:
    """The refusals addressed to ``commander`` on one drone (see the module doc).

    Args:
        ns: the drone's namespace (for the warning line).
        commander: our name on the command lease.
        clock: the node's clock.
    """

    def __init__(self, ns: str, commander: str, clock: Clock) -> None:
        self.ns = ns
        self.commander = commander
        self.clock = clock
        self.recent: collections.deque[Refusal] = collections.deque(maxlen=KEEP)
        self.received = 0
        self.received_at: float | None = None
        self._listeners: list[Callable[[Refusal], None]] = []
        self._warned: dict[tuple[str, str, str], float] = {}
        self._lock = threading.Lock()

    def addressed(self, refusal: Refusal) -> bool:
        """True if ``refusal`` is ours (it names us, or nobody)."""
        return refusal.commander in (self.commander, "")

    def on_refusal(self, refusal: Refusal) -> None:
        """A refusal arrived (the subscription's callback): keep, warn, call back if ours."""
        if not self.addressed(refusal):
            return
        now = self.clock.monotonic()
        with self._lock:
            self.recent.append(refusal)
            self.received += 1
            self.received_at = now
            listeners = list(self._listeners)
            key = (refusal.kind, refusal.what, refusal.limit or refusal.message)
            warn = now - self._warned.get(key, -WARN_AGAIN_S) >= WARN_AGAIN_S
            if warn:
                self._warned[key] = now
        if warn:
            log.warning("%s: %s", self.ns, refusal.text())
        for listener in listeners:
            try:
                listener(refusal)
            except Exception:
                log.exception("%s: on_refusal callback failed", self.ns)

    def listen(self, callback: Callable[[Refusal], None]) -> Callable[[], None]:
        """Call ``callback(refusal)`` for each refusal addressed to us from now on (on the
        subscription's thread: keep it short). Returns a function that stops it."""
        with self._lock:
            self._listeners.append(callback)

        def stop() -> None:
            with self._lock:
                if callback in self._listeners:
                    self._listeners.remove(callback)

        return stop
