"""Matching the Tello's replies to the commands that caused them (pure; time injected).

The Tello answers each command (except ``rc``) with one datagram, in order, without ids: ``ok``,
``error ...``, ``out of range``, ``unknown command: ...``, or a value for read commands
(``battery?`` -> ``87``). Replies can be lost (UDP) or late, so every send is a *slot* in a FIFO:

* a reply goes to the oldest slot that can take it: a value only answers a read (``...?``);
  ``ok`` / ``error`` / ``out of range`` / ``unknown command`` answer anything. Unanswered
  slots it skips lost their reply (counted in ``lost``);
* a slot of a command that is already answered (an earlier or later send of a retried command)
  takes the next reply as a ``duplicate``: the answer to the other send. The sender waits a
  short settle time after a retried or abandoned command for such stray replies, then calls
  :meth:`ReplyMatcher.forget`, so a stray reply is not taken for the next command's answer;
* a slot still unanswered ``stale_after`` s after its command's own timeout is dropped (``lost``);
* a reply with no slot to take it is ``unsolicited``.

:class:`Pending` is one command with its retry schedule: re-sent after ``timeout`` s up to
``attempts`` times; a reply to *any* of its sends answers it.
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass, field

STATUS_PREFIXES = ("ok", "error", "out of range", "unknown command")


def is_read(command: str) -> bool:
    """True for read commands (``battery?``), answered with a value."""
    return command.strip().endswith("?")


def is_status(reply: str) -> bool:
    """True for ok / error / out of range / unknown command replies."""
    return reply.lower().startswith(STATUS_PREFIXES)


def is_ok(reply: str) -> bool:
    """True for an ``ok`` reply."""
    return reply.strip().lower() == "ok"


@dataclass
class Pending:
    """One command waiting for its reply, with its retry schedule (monotonic s).

    Attributes:
        reply: the reply text once answered, else None.
        sent: how many times it was sent.
    """

    command: str
    timeout: float = 1.0
    attempts: int = 3
    reply: str | None = None
    sent: int = 0
    _next_send: float = -math.inf
    _deadline: float = math.inf

    @property
    def read(self) -> bool:
        return is_read(self.command)

    def due(self, now: float) -> bool:
        """True if the command must be sent (again) now; counts the send."""
        if self.reply is not None or self.sent >= self.attempts or now < self._next_send:
            return False
        self.sent += 1
        self._next_send = now + self.timeout
        self._deadline = now + self.timeout
        return True

    def finished(self, now: float) -> bool:
        """Answered, or out of attempts and the last wait is over."""
        return self.reply is not None or (self.sent >= self.attempts and now >= self._deadline)

    def wake_at(self, now: float) -> float:
        """When to look again (next send or the deadline)."""
        return max(now, min(self._next_send, self._deadline))


@dataclass
class _Slot:
    pending: Pending
    sent_at: float


@dataclass
class ReplyMatcher:
    """The FIFO of sends waiting for replies (see module docstring)."""

    stale_after: float = 2.0
    lost: int = 0
    duplicates: int = 0
    unsolicited: int = 0
    _slots: deque[_Slot] = field(default_factory=deque)

    def sent(self, pending: Pending, now: float) -> None:
        """``pending`` was just sent (once more)."""
        self._slots.append(_Slot(pending, now))

    def expire(self, now: float) -> None:
        """Drop slots past their timeout + ``stale_after`` s (unanswered ones count as lost)."""
        while self._slots and (
            now - self._slots[0].sent_at > self._slots[0].pending.timeout + self.stale_after
        ):
            if self._slots.popleft().pending.reply is None:
                self.lost += 1

    def forget(self, pending: Pending) -> None:
        """Drop every slot of ``pending`` (finished; its stray replies have had their time)."""
        self._slots = deque(s for s in self._slots if s.pending is not pending)

    def waiting(self) -> int:
        """Sends still in the FIFO."""
        return len(self._slots)

    def on_reply(self, text: str, now: float) -> Pending | None:
        """Feed one reply; returns the command it answers (None: duplicate or unsolicited)."""
        self.expire(now)
        status = is_status(text)
        while self._slots:
            slot = self._slots.popleft()
            if slot.pending.reply is not None:
                self.duplicates += 1
                return None
            if status or slot.pending.read:
                slot.pending.reply = text
                return slot.pending
            self.lost += 1  # a value cannot answer it: its own reply was lost
        self.unsolicited += 1
        return None
