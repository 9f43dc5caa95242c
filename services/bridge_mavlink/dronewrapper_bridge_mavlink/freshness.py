"""Which received MAVLink messages are new (pure): duplicates and stale datagrams are dropped.

UDP can duplicate and reorder datagrams. Republishing them would publish a pose older than one
already published, or the same pose twice as a new one (the pose rate went from 50 to 62 Hz
under 30 % duplication). Two checks, per sender (source address, system id, component id):

- MAVLink ``seq`` (one 8-bit counter per sender): a message identical (seq and bytes) to one of
  the last ``REORDER_WINDOW`` received is a duplicate; one whose seq is 1 to ``REORDER_WINDOW``
  behind the newest (mod 256) arrived late: both dropped. A larger step forward is loss, which
  is fine. (A sender that never increments seq still gets every distinct message through.)
- ``time_boot_ms`` (messages that carry it): per message type, a message not newer than the
  newest one of its type is dropped, unless it went back by more than ``REBOOT_JUMP_MS`` (the
  autopilot rebooted).

A sender silent for ``SILENCE_RESET_S`` starts afresh (a restarted autopilot restarts its seq
and its clock; a restarted simulator also has a new UDP source port, so a new sender).
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass, field
from typing import Any

REORDER_WINDOW = 64  # seq values behind the newest that count as late or duplicated
REBOOT_JUMP_MS = 10_000  # a time_boot_ms going back further than this is a reboot
SILENCE_RESET_S = 2.0  # s of silence after which a sender's history is forgotten
MAX_SENDERS = 64  # bounded memory: the longest-silent sender is forgotten beyond this


@dataclass
class _Sender:
    seq: int
    last_seen: float
    boot_ms: dict[str, int] = field(default_factory=dict)
    recent: deque[tuple[int, int]] = field(default_factory=lambda: deque(maxlen=REORDER_WINDOW))


@dataclass
class Verdict:
    """Whether to use a message, and why not (``reason`` "" when it is new)."""

    new: bool
    reason: str = ""


class Freshness:
    """Decides, message by message, whether a received message is new (time injected)."""

    def __init__(self) -> None:
        self._senders: dict[tuple[Any, int, int], _Sender] = {}
        self.duplicates = 0
        self.stale = 0

    def check(
        self,
        address: Any,
        system: int,
        component: int,
        seq: int,
        kind: str,
        boot_ms: int | None,
        now: float,
        payload: bytes = b"",
    ) -> Verdict:
        """Judge one message.

        Args:
            address: where it came from (``(host, port)`` for UDP, None when unknown).
            system, component, seq: its MAVLink header.
            kind: its type name (``LOCAL_POSITION_NED``).
            boot_ms: its ``time_boot_ms`` field, None if it has none.
            now: monotonic time (s).
            payload: its bytes (``get_msgbuf()``), to tell a duplicate from a new message that
                reuses a seq.
        """
        key = (address, system, component)
        fingerprint = (seq, hash(payload))
        sender = self._senders.get(key)
        if sender is None or now - sender.last_seen > SILENCE_RESET_S:
            sender = _Sender(seq=seq, last_seen=now)
            sender.recent.append(fingerprint)
            self._remember(key, sender, now)
            if boot_ms is not None:
                sender.boot_ms[kind] = boot_ms
            return Verdict(True)
        if fingerprint in sender.recent:
            self.duplicates += 1
            return Verdict(False, f"duplicate of seq {seq}")
        behind = (sender.seq - seq) % 256
        if 0 < behind <= REORDER_WINDOW:
            self.stale += 1
            return Verdict(False, f"seq {seq} is {behind} behind the newest {sender.seq}")
        sender.recent.append(fingerprint)
        sender.seq = seq
        sender.last_seen = now
        if boot_ms is not None:
            newest = sender.boot_ms.get(kind)
            if newest is not None and newest - REBOOT_JUMP_MS <= boot_ms <= newest:
                self.stale += 1
                return Verdict(False, f"{kind} time_boot_ms {boot_ms} not after {newest}")
            sender.boot_ms[kind] = boot_ms
        return Verdict(True)

    def _remember(self, key: tuple[Any, int, int], sender: _Sender, now: float) -> None:
        self._senders[key] = sender
        if len(self._senders) > MAX_SENDERS:
            oldest = min(self._senders, key=lambda k: self._senders[k].last_seen)
            del self._senders[oldest]


def boot_ms_of(msg: Any) -> int | None:
    """The ``time_boot_ms`` of a pymavlink message, None when it has none."""
    value = getattr(msg, "time_boot_ms", None)
    return value if isinstance(value, int) else None
