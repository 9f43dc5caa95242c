"""COMMAND_LONG / COMMAND_ACK logic: retries, confirmation counter, ack matching, de-duplication.

Pure: time is passed in (monotonic seconds). The node sends what :meth:`PendingCommand.due`
returns and feeds every COMMAND_ACK to :meth:`AckRouter.on_ack`.

* A command is re-sent every ``ack_timeout`` seconds, up to ``attempts`` times, with the
  ``confirmation`` field incremented on each re-send (as MAVLink asks).
* IN_PROGRESS (5) is not final: it extends the wait by ``in_progress_timeout``.
* PX4 acknowledges DO_SET_MODE twice, and the two acks mean different things: its MAVLink
  receiver answers ACCEPTED at once ("received"), then the commander sends the real result
  (TEMPORARILY_REJECTED for a mode it cannot enter). A command sent with ``expected_acks=2``
  therefore takes a first ACCEPTED as provisional and waits up to ``final_ack_timeout`` for the
  second; a refusal, in either ack, is final. If no second ack comes, the command finishes
  ACCEPTED but not :attr:`PendingCommand.confirmed` (the caller must confirm another way, e.g.
  by the mode in HEARTBEAT).
* An ack for a command id with nothing pending is a duplicate (if that id completed within
  ``dedup_window`` s) or unsolicited; either way it is counted and ignored. To keep a late
  duplicate from being taken for the ack of the next command with the same id, the next one is
  not sent before :meth:`AckRouter.quiet_until`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from pymavlink.dialects.v20 import common as mavlink
from pymavlink.dialects.v20.common import (
    MAV_RESULT_ACCEPTED,
    MAV_RESULT_IN_PROGRESS,
)

RESULT_NO_ACK = -1  # not a MAV_RESULT: no COMMAND_ACK arrived


def _enum_name(enum: str, value: int, prefix: str) -> str | None:
    entry = mavlink.enums[enum].get(value)
    return entry.name.removeprefix(prefix) if entry is not None else None


def result_name(result: int) -> str:
    """MAV_RESULT as text (``ACCEPTED``, ``DENIED`` ..., ``NO_ACK`` when none arrived)."""
    if result == RESULT_NO_ACK:
        return "NO_ACK"
    return _enum_name("MAV_RESULT", result, "MAV_RESULT_") or f"RESULT_{result}"


def command_name(command: int) -> str:
    """MAV_CMD as text."""
    return _enum_name("MAV_CMD", command, "MAV_CMD_") or f"MAV_CMD_{command}"


@dataclass(frozen=True)
class Command:
    """One MAV_CMD with its seven params, as a COMMAND_LONG carries it (the sender addresses
    it: :class:`~dronewrapper_bridge_mavlink.outgoing.CommandLong`)."""

    command: int
    params: tuple[float, float, float, float, float, float, float]
    confirmation: int = 0


def command_long(command: int, *params: float) -> Command:
    """A COMMAND_LONG with up to 7 params (missing ones are 0)."""
    if len(params) > 7:
        raise ValueError("COMMAND_LONG takes at most 7 params")
    padded = tuple(float(p) for p in params) + (0.0,) * (7 - len(params))
    return Command(command, padded)  # type: ignore[arg-type]


@dataclass
class PendingCommand:
    """One command waiting for its COMMAND_ACK, with its retry schedule.

    Attributes:
        expected_acks: acks the autopilot sends for this command (2: PX4's DO_SET_MODE).
        final_ack_timeout: s to wait for the last expected ack after a provisional ACCEPTED.
        result: MAV_RESULT once final, else RESULT_NO_ACK.
        sent: how many times it was sent.
        acks: how many acks arrived.
        confirmed: False while (or when it ended) ACCEPTED only provisionally.
    """

    cmd: Command
    attempts: int = 3
    ack_timeout: float = 1.0
    in_progress_timeout: float = 5.0
    expected_acks: int = 1
    final_ack_timeout: float = 1.0
    result: int = RESULT_NO_ACK
    sent: int = 0
    acks: int = 0
    confirmed: bool = True
    done: bool = False
    acked_at: float | None = None
    _next_send: float = -math.inf
    _deadline: float = math.inf

    def due(self, now: float) -> Command | None:
        """The COMMAND_LONG to send now (first send or a retry), or None."""
        if self.done or self.sent >= self.attempts or now < self._next_send:
            return None
        msg = Command(self.cmd.command, self.cmd.params, confirmation=self.sent)
        self.sent += 1
        self._next_send = now + self.ack_timeout
        self._deadline = now + self.ack_timeout
        return msg

    def on_ack(self, result: int, now: float) -> None:
        """Feed the ack's MAV_RESULT: IN_PROGRESS extends the wait; a first ACCEPTED of a
        command acknowledged twice waits for the second; anything else is final."""
        self.acked_at = now
        self.result = result
        self.acks += 1
        if result == MAV_RESULT_IN_PROGRESS:
            self._next_send = math.inf  # the autopilot is working on it: do not re-send
            self._deadline = now + self.in_progress_timeout
            return
        if result == MAV_RESULT_ACCEPTED and self.acks < self.expected_acks:
            self.confirmed = False  # "received": the real answer is still to come
            self._next_send = math.inf
            self._deadline = now + self.final_ack_timeout
            return
        self.confirmed = True
        self.done = True

    def finished(self, now: float) -> bool:
        """True once acked with a final result or out of attempts and time."""
        if self.done:
            return True
        if not self.confirmed and now >= self._deadline:
            self.done = True  # ACCEPTED once; the final answer never came
        elif self.sent >= self.attempts and now >= self._deadline:
            self.done = True
            if self.result == MAV_RESULT_IN_PROGRESS:
                self.result = RESULT_NO_ACK
        elif self.result == MAV_RESULT_IN_PROGRESS and now >= self._deadline:
            self.done = True
            self.result = RESULT_NO_ACK
        return self.done

    def wake_at(self, now: float) -> float:
        """When the sender should look again (next retry or deadline)."""
        return max(now, min(self._next_send, self._deadline))


@dataclass
class AckRouter:
    """Routes COMMAND_ACKs to pending commands by command id; drops duplicates.

    Attributes:
        duplicates: acks for a command id that completed within ``dedup_window`` s.
        unsolicited: acks nobody was waiting for.
    """

    dedup_window: float = 0.3
    duplicates: int = 0
    unsolicited: int = 0
    _pending: dict[int, PendingCommand] = field(default_factory=dict)
    _completed_at: dict[int, float] = field(default_factory=dict)

    def quiet_until(self, command: int) -> float:
        """Earliest time a new command with this id may be sent (duplicates have passed)."""
        return self._completed_at.get(command, -math.inf) + self.dedup_window

    def register(self, pending: PendingCommand) -> None:
        """Start waiting for ``pending``'s ack (one pending command per id)."""
        command = pending.cmd.command
        if command in self._pending:
            raise RuntimeError(f"{command_name(command)} is already pending")
        self._pending[command] = pending

    def release(self, pending: PendingCommand, now: float) -> None:
        """Stop waiting for ``pending`` (finished): later acks for its id are duplicates."""
        command = pending.cmd.command
        if self._pending.get(command) is pending:
            del self._pending[command]
        if pending.acked_at is not None or pending.sent:
            self._completed_at[command] = now

    def on_ack(self, command: int, result: int, now: float) -> str:
        """Feed one COMMAND_ACK: returns ``matched``, ``duplicate`` or ``unsolicited``."""
        pending = self._pending.get(command)
        if pending is not None and not pending.done:
            pending.on_ack(result, now)
            return "matched"
        if now - self._completed_at.get(command, -math.inf) <= self.dedup_window or (
            pending is not None and pending.done
        ):
            self.duplicates += 1
            return "duplicate"
        self.unsolicited += 1
        return "unsolicited"
