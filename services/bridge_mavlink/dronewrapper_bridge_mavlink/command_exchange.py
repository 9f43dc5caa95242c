"""The bridge's commands to the autopilot as a part the core owns (:class:`Commands`): each
COMMAND_LONG sent with its retries until its final COMMAND_ACK (the rules: commands.py), one
exchange at a time, none before late duplicate acks of the same command id have passed, and a
refusal explained with the autopilot's own words (its STATUSTEXT warnings since the command).

The part holds the acks' routing (:class:`~dronewrapper_bridge_mavlink.commands.AckRouter`) and
sees only what it needs of the core (:class:`CommandPort`: the time, the one command slot the
core's operations share, the autopilot's address, the outbox, the texts heard). Times are the
core's monotonic s.
"""

from __future__ import annotations

from collections.abc import Generator, Sequence
from typing import Protocol

from pymavlink.dialects.v20 import common as mavlink

from dronewrapper.msgs.mavros import SEVERITY_WARNING
from dronewrapper.msgs.mavros import StatusText as StatusTextMsg
from dronewrapper_bridge_base.core_view import CommandSlot
from dronewrapper_bridge_mavlink import commands as cmds
from dronewrapper_bridge_mavlink.config import Config
from dronewrapper_bridge_mavlink.outgoing import AutopilotPort, CommandLong

ACCEPTED = mavlink.MAV_RESULT_ACCEPTED
BUSY_POLL_S = 0.05  # a command waiting for the slot looks again this often


class CommandPort(AutopilotPort, CommandSlot, Protocol):
    """What a command exchange uses of the core besides its time, the autopilot's address,
    the outbox and the command slot: the texts heard (each with its arrival, monotonic s)."""

    @property
    def recent_texts(self) -> Sequence[tuple[float, StatusTextMsg]]: ...


class Commands:
    """COMMAND_LONG exchanges with the autopilot (module docstring).

    Args:
        port: the core's side an exchange uses (:class:`CommandPort`).
        config: the bridge's; its ``command_attempts`` (sends of a COMMAND_LONG),
            ``command_ack_timeout`` and ``final_ack_timeout`` (s to wait for an ack, for the
            second ack of a command acked twice) and ``reason_wait`` (s a refusal waits for
            the warning that explains it).
    """

    def __init__(self, port: CommandPort, config: Config) -> None:
        self._port = port
        self.config = config
        self.acks = cmds.AckRouter()

    def on_ack(self, command: int, result: int) -> str:
        """One COMMAND_ACK answering the bridge: ``matched``, ``duplicate`` or ``unsolicited``."""
        return self.acks.on_ack(command, result, self._port.now)

    def exchange(
        self, command: int, *params: float, expected_acks: int = 1
    ) -> Generator[float, None, tuple[cmds.PendingCommand, str]]:
        """Send a COMMAND_LONG and wait for its final ack (the second of ``expected_acks`` = 2,
        see commands.py): the finished command and an explanation (with the autopilot's
        STATUSTEXT reason for a refusal)."""
        port, acks, config = self._port, self.acks, self.config
        pending = cmds.PendingCommand(
            cmds.command_long(command, *params),
            attempts=config.command_attempts,
            ack_timeout=config.command_ack_timeout,
            expected_acks=expected_acks,
            final_ack_timeout=config.final_ack_timeout,
        )
        while port.command_busy or port.now < acks.quiet_until(command):
            yield port.now + BUSY_POLL_S if port.command_busy else acks.quiet_until(command)
        port.take_command_slot()
        started = port.now
        acks.register(pending)
        try:
            while True:
                msg = pending.due(port.now)
                if msg is not None:
                    port.send(CommandLong(*port.target(), command, msg.confirmation, msg.params))
                if pending.finished(port.now):
                    break
                yield pending.wake_at(port.now)
        finally:
            acks.release(pending, port.now)
            port.release_command_slot()
        name = cmds.command_name(command)
        if pending.result == ACCEPTED:
            return pending, f"{name} accepted"
        if pending.result == cmds.RESULT_NO_ACK:
            return pending, f"{name}: no COMMAND_ACK after {pending.sent} attempt(s)"
        reason = yield from self.reason_since(started)
        text = f"{name} refused: {cmds.result_name(pending.result)}"
        return pending, f"{text} ({reason})" if reason else text

    def reason_since(self, started: float) -> Generator[float, None, str]:
        """The autopilot's warnings since ``started``, waiting up to ``reason_wait`` s for one."""
        port = self._port
        deadline = port.now + self.config.reason_wait
        while True:
            texts = [
                text.text
                for at, text in port.recent_texts
                if at >= started - 0.05
                and text.severity <= SEVERITY_WARNING
                and text.header.frame_id != "bridge"
            ]
            if texts or port.now >= deadline:
                return "; ".join(texts)
            yield deadline
