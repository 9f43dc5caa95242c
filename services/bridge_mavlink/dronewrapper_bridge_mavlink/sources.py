"""One autopilot per system id (pure): a second sender with the same id is flagged, not mixed.

Two simulators (or a simulator and a real autopilot) sending to the same UDP port with the
same system id would merge into one stream: poses jumping between two aircraft, commands going
to whichever spoke last, the link looking lost for seconds. The first address heard for
a system id is its autopilot; while it keeps talking, messages with that id from any other
address are dropped and reported. When it has been silent for ``TAKEOVER_SILENCE_S`` the new
address takes over (an autopilot restarted on a new UDP source port).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

TAKEOVER_SILENCE_S = 2.0


@dataclass
class _Owner:
    address: Any
    last_seen: float


@dataclass
class SourceVerdict:
    """``accept``: use the message. ``flag``: a sentence to report (first time only) or ""."""

    accept: bool
    flag: str = ""


class AutopilotSources:
    """Tracks which address speaks for each system id (time injected, monotonic s)."""

    def __init__(self) -> None:
        self._owners: dict[int, _Owner] = {}
        self._flagged: set[tuple[int, Any]] = set()
        self.intruder_messages = 0

    def owner(self, system: int) -> Any:
        """The address currently accepted for ``system`` (None if none yet)."""
        owner = self._owners.get(system)
        return owner.address if owner is not None else None

    def check(self, address: Any, system: int, now: float) -> SourceVerdict:
        """Whether a message from ``address`` claiming ``system`` may be used."""
        if address is None:  # serial or TCP: one peer by construction
            return SourceVerdict(True)
        owner = self._owners.get(system)
        if owner is None:
            self._owners[system] = _Owner(address, now)
            return SourceVerdict(True)
        if owner.address == address:
            owner.last_seen = now
            return SourceVerdict(True)
        if now - owner.last_seen >= TAKEOVER_SILENCE_S:
            previous = owner.address
            self._owners[system] = _Owner(address, now)
            self._flagged.discard((system, address))
            return SourceVerdict(
                True,
                f"system {system} now speaks from {_fmt(address)} "
                f"({_fmt(previous)} silent for {now - owner.last_seen:.1f} s)",
            )
        self.intruder_messages += 1
        if (system, address) in self._flagged:
            return SourceVerdict(False)
        if len(self._flagged) < 64:
            self._flagged.add((system, address))
        return SourceVerdict(
            False,
            f"a second autopilot with system id {system} at {_fmt(address)} "
            f"(the autopilot is at {_fmt(owner.address)}): its messages are ignored",
        )


def _fmt(address: Any) -> str:
    if isinstance(address, tuple) and len(address) >= 2:
        return f"{address[0]}:{address[1]}"
    return str(address)
