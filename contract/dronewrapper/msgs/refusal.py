"""What a bridge refused or overrode, told to the commander whose input it was.

A setpoint has no reply, so a setpoint the bridge does not fly (outside the envelope, from a
commander without the lease, arriving late, malformed) and a breach that overrides whoever
commands are published on ``{ns}/dronewrapper/refusal`` (:data:`~.registry.REFUSAL`), one
message naming the commander, the rule, the limit and the figures. A request that has a reply
(take-off, a mode change) carries its refusal in that reply instead.

A stream of identical refusals (a 30 Hz setpoint stream refused for the same limit) is
published once at once, then at most once per :data:`REPEAT_PERIOD_S` while it repeats;
``count`` says how many refusals each message stands for.
"""

from __future__ import annotations

import msgspec

from dronewrapper.msgs.std import Header

ENVELOPE = "envelope"
"""The target is outside the safety envelope (``limit``: the envelope's field, e.g.
``max_altitude``, ``fence``)."""
LEASE = "lease"
"""Another commander holds the command lease (``limit``: ``command_lease``)."""
LATE = "late"
"""The setpoint arrived later than its commander's usual lag allows (``limit``:
``late_setpoint_s``)."""
VALIDATION = "validation"
"""The setpoint is malformed or beyond the bridge's bounds (``limit``: the field or bound)."""
BREACH = "breach"
"""The aircraft left the envelope; the bridge's breach action overrides the commander
(``limit``: the envelope's field crossed; ``action``: hold, return or land)."""

KINDS = (ENVELOPE, LEASE, LATE, VALIDATION, BREACH)

REPEAT_PERIOD_S = 1.0
"""Identical refusals (same commander, kind, input and limit) are published at most this often
(s) after the first, which is published at once."""


class Refusal(msgspec.Struct, kw_only=True, frozen=True):
    """One refusal (or override) by a bridge.

    Attributes:
        header: ``stamp``: when the bridge refused (its clock, Unix s).
        commander: whose input it was (the ``commander`` attachment; ``""``: nobody known,
            e.g. a breach while nobody commands).
        kind: one of :data:`KINDS`.
        what: the refused input (``setpoint``) or what was overridden (``command``).
        limit: the limit named (an envelope field, ``command_lease``, ``late_setpoint_s``,
            a setpoint field); ``""`` when none applies.
        message: the bridge's words, with the figures, for a person.
        action: what the bridge does instead (a breach's ``hold``/``return``/``land``; ``""``:
            nothing, the input is dropped and the aircraft keeps what it was doing).
        count: how many identical refusals this message stands for (>= 1; see module doc).
    """

    header: Header = msgspec.field(default_factory=Header)
    commander: str = ""
    kind: str = ""
    what: str = "setpoint"
    limit: str = ""
    message: str = ""
    action: str = ""
    count: int = 1

    def text(self) -> str:
        """One line for a person: ``setpoint refused (envelope, max_altitude): ...``."""
        named = ", ".join(part for part in (self.kind, self.limit) if part)
        repeated = f" (x{self.count})" if self.count > 1 else ""
        verb = "overridden" if self.kind == BREACH else "refused"
        return f"{self.what} {verb} ({named}){repeated}: {self.message}"
