"""A bridge's command guard: the command lease applied to setpoints and command services.

Aircraft-independent, so every bridge uses it (bridge_tello; bridge_mavlink has the same logic
in its own guard.py, which can become an import of this one).

With ``command_lease`` on, the bridge obeys one commander at a time (see
:mod:`dronewrapper.security.lease`): the commander is the ``commander`` attachment of the
setpoint or request being handled. Another commander is refused (setpoints dropped and
counted, commands answered with a ``lease`` error) until it takes the lease over through
``{ns}/dronewrapper/lease``; every change of holder is logged and shown on ``State.commander``.
With the lease off, everything is admitted and the lease service says so.
"""

from __future__ import annotations

import logging
import threading
import time
from collections.abc import Callable

from dronewrapper.msgs import registry
from dronewrapper.msgs.lease import LeaseReply, LeaseRequest
from dronewrapper.runtime import Node, ServiceError
from dronewrapper.runtime.caller import current_commander
from dronewrapper.security.lease import CommandLease, LeaseDecision

log = logging.getLogger("lease")

LEASE_ACTIONS = ("take", "take_over", "release")


class CommandGuard:
    """Admits setpoints and commands from the lease holder only (when ``enabled``).

    Args:
        enabled: enforce the lease; off, everything is admitted.
        ttl_s: a holder silent this long loses the lease (s).
        on_change: called after the holder changed (the bridge republishes State).
        clock: monotonic seconds (injected for tests).
    """

    def __init__(
        self,
        *,
        enabled: bool,
        ttl_s: float,
        on_change: Callable[[], None] | None = None,
        clock: Callable[[], float] = time.monotonic,
    ) -> None:
        self.enabled = enabled
        self.lease = CommandLease(ttl_s)
        self.refused_setpoints = 0
        self.refused_commands = 0
        self._on_change = on_change
        self._clock = clock
        self._lock = threading.Lock()
        self._last_refusal_log = float("-inf")

    def holder(self) -> str:
        """The commander holding the lease now (``""`` when free or the lease is off)."""
        if not self.enabled:
            return ""
        with self._lock:
            return self.lease.current(self._clock())

    def _note(self, decision: LeaseDecision, commander: str) -> None:
        if decision.event:
            log.warning(
                "command lease %s: %s (was %s)",
                decision.event,
                decision.holder or "nobody",
                decision.previous or "nobody",
            )
            if self._on_change is not None:
                self._on_change()
        elif not decision.accepted:
            now = self._clock()
            if now - self._last_refusal_log >= 2.0:
                self._last_refusal_log = now
                log.warning("refused %r: %s", commander, decision.reason(commander))

    def admit_setpoint(self) -> bool:
        """True if the setpoint being handled comes from the holder (or the lease is off)."""
        if not self.enabled:
            return True
        commander = current_commander()
        with self._lock:
            decision = self.lease.admit(commander, self._clock())
        if not decision.accepted:
            self.refused_setpoints += 1
        self._note(decision, commander)
        return decision.accepted

    def admit_command(self, what: str) -> None:
        """Raise ServiceError (code ``lease``) unless the request comes from the holder."""
        if not self.enabled:
            return
        commander = current_commander()
        with self._lock:
            decision = self.lease.admit(commander, self._clock())
        self._note(decision, commander)
        if not decision.accepted:
            self.refused_commands += 1
            raise ServiceError(f"{what} refused: {decision.reason(commander)}", "lease")

    def handle_lease(self, request: LeaseRequest) -> LeaseReply:
        """The ``{ns}/dronewrapper/lease`` service: take, take over or release."""
        if request.action not in LEASE_ACTIONS:
            raise ValueError(f"action must be one of {', '.join(LEASE_ACTIONS)}")
        if not self.enabled:
            return LeaseReply(granted=True, message="the command lease is off on this bridge")
        commander = current_commander()
        now = self._clock()
        with self._lock:
            if request.action == "take_over":
                decision = self.lease.take_over(commander, now)
            elif request.action == "take":
                decision = self.lease.admit(commander, now)
            else:
                decision = self.lease.release(commander, now)
        self._note(decision, commander)
        message = "ok" if decision.accepted else decision.reason(commander or "anonymous")
        return LeaseReply(
            granted=decision.accepted,
            holder=decision.holder,
            previous=decision.previous,
            message=message,
        )

    def serve(self, node: Node) -> None:
        """Serve the lease service on ``node``."""
        node.serve(registry.COMMAND_LEASE, self.handle_lease)
