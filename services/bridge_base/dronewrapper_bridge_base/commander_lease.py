"""The commander lease: at most one commander per drone at a time (pure logic, time injected).

Every setpoint and command names its commander (the ``commander`` attachment the SDK adds, see
:mod:`dronewrapper.runtime.caller`). :class:`CommanderLease` says whether to obey it:

- nobody holds the lease, or the holder has been silent for ``ttl_s``: the commander takes it;
- the holder: obeyed, and the lease is renewed;
- anyone else: refused, until it takes the lease over explicitly (:meth:`take_over`), which is
  logged and shown on ``State.commander``.

:class:`LeaseGate` is that lease applied by a bridge's pure core to setpoints, commands and the
``{ns}/dronewrapper/lease`` service; off (``ttl_s`` None), it admits everything.

The lease coordinates authorised operators (the router's access control keeps everyone else
out). A commander's name is the one its key is bound to when the key carries one (a
certificate's name, which the router's access control enforces on a secure graph), else what
its attachment says (on a secure router, only the drone's own local processes send those).
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass
from typing import Any

from dronewrapper.msgs.lease import LeaseReply, LeaseRequest
from dronewrapper.runtime.errors import ServiceError

DEFAULT_TTL_S = 10.0
ANONYMOUS = "anonymous"
LEASE_ACTIONS = ("take", "take_over", "release")


@dataclass(frozen=True)
class LeaseDecision:
    """The answer for one command: obey it or not, who holds the lease, what changed."""

    accepted: bool
    holder: str
    event: str = ""  # "", "acquired", "expired", "taken_over", "released"
    previous: str = ""

    def reason(self, commander: str) -> str:
        """Why a refused command was refused (for the reply and the log)."""
        return (
            f"{self.holder!r} holds the command lease; {commander!r} must take it over "
            "explicitly (DroneWrapper.take_command())"
        )


class CommanderLease:
    """Who may command the drone now.

    Args:
        ttl_s: the holder loses the lease after this long without a setpoint or command (s).
    """

    def __init__(self, ttl_s: float = DEFAULT_TTL_S) -> None:
        if not ttl_s > 0:
            raise ValueError(f"lease ttl_s must be > 0, got {ttl_s}")
        self.ttl_s = ttl_s
        self.holder = ""
        self._last_s = -math.inf

    def current(self, now: float) -> str:
        """The holder at ``now`` (``""`` when free or lapsed)."""
        return self.holder if self.holder and now - self._last_s < self.ttl_s else ""

    def admit(self, commander: str, now: float) -> LeaseDecision:
        """Whether to obey a setpoint or command from ``commander`` at ``now`` (s)."""
        commander = commander or ANONYMOUS
        holder = self.current(now)
        if holder == commander:
            self._last_s = now
            return LeaseDecision(True, commander)
        if not holder:
            previous, self.holder, self._last_s = self.holder, commander, now
            event = "expired" if previous and previous != commander else "acquired"
            return LeaseDecision(True, commander, event, previous)
        return LeaseDecision(False, holder)

    def take_over(self, commander: str, now: float) -> LeaseDecision:
        """``commander`` takes the lease, whoever held it (explicit; the caller logs it)."""
        commander = commander or ANONYMOUS
        previous = self.current(now)
        self.holder, self._last_s = commander, now
        event = "taken_over" if previous and previous != commander else "acquired"
        return LeaseDecision(True, commander, event, previous)

    def release(self, commander: str, now: float) -> LeaseDecision:
        """The holder gives the lease back (anyone else: refused)."""
        commander = commander or ANONYMOUS
        holder = self.current(now)
        if holder and holder != commander:
            return LeaseDecision(False, holder)
        self.holder, self._last_s = "", -math.inf
        return LeaseDecision(True, "", "released", holder)


class LeaseGate:
    """The lease applied to a bridge's inputs (pure; ``now`` monotonic s).

    Args:
        ttl_s: a holder silent this long loses the lease (s); None: the lease is off and
            everything is admitted.
        log: where changes of holder and (at most every 2 s) refusals are logged.

    Attributes:
        refused_setpoints, refused_commands: how many were refused so far.
    """

    def __init__(self, ttl_s: float | None, log: logging.Logger) -> None:
        self.lease = CommanderLease(ttl_s) if ttl_s is not None else None
        self.refused_setpoints = 0
        self.refused_commands = 0
        self._log = log
        self._last_refusal_log = -math.inf

    def holder(self, now: float) -> str:
        """The commander holding the lease at ``now`` (``""`` when free or the lease is off)."""
        return self.lease.current(now) if self.lease is not None else ""

    def admit_setpoint(self, commander: str, now: float) -> bool:
        """True if a setpoint from ``commander`` may be flown."""
        if self.lease is None:
            return True
        decision = self._note(self.lease.admit(commander, now), commander, now)
        if not decision.accepted:
            self.refused_setpoints += 1
        return decision.accepted

    def command_refusal(self, commander: str, what: str, now: float) -> ServiceError | None:
        """None if command ``what`` from ``commander`` may run, else its refusal (code
        ``lease``)."""
        if self.lease is None:
            return None
        decision = self._note(self.lease.admit(commander, now), commander, now)
        if decision.accepted:
            return None
        self.refused_commands += 1
        return ServiceError(decision.reason(commander), "lease")  # the SDK names ``what``

    def handle(self, request: LeaseRequest, commander: str, now: float) -> LeaseReply:
        """The lease service: take, take over or release (ValueError for another action)."""
        if request.action not in LEASE_ACTIONS:
            raise ValueError(f"action must be one of {', '.join(LEASE_ACTIONS)}")
        if self.lease is None:
            return LeaseReply(granted=True, message="the command lease is off on this bridge")
        if request.action == "take_over":
            decision = self.lease.take_over(commander, now)
        elif request.action == "take":
            decision = self.lease.admit(commander, now)
        else:
            decision = self.lease.release(commander, now)
        self._note(decision, commander, now)
        message = "ok" if decision.accepted else decision.reason(commander or ANONYMOUS)
        return LeaseReply(
            granted=decision.accepted,
            holder=decision.holder,
            previous=decision.previous,
            message=message,
        )

    def _note(self, decision: LeaseDecision, commander: str, now: float) -> LeaseDecision:
        if decision.event:
            self._log.warning(
                "command lease %s: %s (was %s)",
                decision.event,
                decision.holder or "nobody",
                decision.previous or "nobody",
            )
        elif not decision.accepted and now - self._last_refusal_log >= 2.0:
            self._last_refusal_log = now
            self._log.warning("refused %r: %s", commander, decision.reason(commander))
        return decision


def commander_rules(config: Any) -> dict[str, Any]:
    """The commander rules a bridge's config sets for its core (``PureCore``'s keywords): the
    lease's ttl (s; None when ``command_lease`` is off) and the late-setpoint threshold (s)."""
    ttl = config.command_lease_ttl_s if config.command_lease else None
    return {"lease_ttl_s": ttl, "late_setpoint_s": config.late_setpoint_s}
