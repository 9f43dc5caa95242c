"""The command lease: at most one commander per drone at a time (pure logic, time injected).

A bridge keeps one :class:`CommandLease`. Every setpoint and command names its commander (the
``commander`` attachment the SDK adds, see :mod:`dronewrapper.runtime.caller`); the lease says
whether to obey it:

- nobody holds the lease, or the holder has been silent for ``ttl_s``: the commander takes it;
- the holder: obeyed, and the lease is renewed;
- anyone else: refused, until it takes the lease over explicitly (:meth:`take_over`), which is
  logged and shown on ``State.commander``.

The lease coordinates authorised operators (the router's access control keeps everyone else
out); it is not an authentication mechanism by itself: a commander's name is what its SDK says.
"""

from __future__ import annotations

from dataclasses import dataclass

DEFAULT_TTL_S = 10.0
ANONYMOUS = "anonymous"


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


class CommandLease:
    """Who may command the drone now.

    Args:
        ttl_s: the holder loses the lease after this long without a setpoint or command (s).
    """

    def __init__(self, ttl_s: float = DEFAULT_TTL_S) -> None:
        if not ttl_s > 0:
            raise ValueError(f"lease ttl_s must be > 0, got {ttl_s}")
        self.ttl_s = ttl_s
        self.holder = ""
        self._last_s = float("-inf")

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
        self.holder, self._last_s = "", float("-inf")
        return LeaseDecision(True, "", "released", holder)
