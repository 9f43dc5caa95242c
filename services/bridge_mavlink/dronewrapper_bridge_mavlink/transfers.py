"""The mission protocol as a part the core owns (:class:`Transfers`): one transfer at a time
over the link (an upload, a download or a clear of missions, fences or rally points), the
others waiting their turn; the running one is fed the autopilot's mission messages.

Each machine of :mod:`~dronewrapper_bridge_mavlink.mission_transfer` is made when its turn
comes, for the autopilot's address then, with the bridge's re-send ``timeout`` (s) and
``attempts``; its messages go to the outbox. The part sees only what it needs of the core
(:class:`~.outgoing.AutopilotPort`: the time, the autopilot's address, the outbox).
"""

from __future__ import annotations

from collections.abc import Callable, Generator
from typing import Any, TypeVar

from dronewrapper_bridge_mavlink import mission_transfer as mt
from dronewrapper_bridge_mavlink.outgoing import AutopilotPort

T = TypeVar("T", bound=mt.Transfer)

WAIT_S = 0.05
"""A transfer waiting for its turn looks again this often (s)."""


class Transfers:
    """One mission-protocol transfer at a time (module docstring).

    Args:
        port: the core's side a transfer uses.
        timeout: s without an answer before a message is sent again (1.5).
        attempts: sends of one message before the transfer gives up (5).
    """

    def __init__(self, port: AutopilotPort, *, timeout: float = 1.5, attempts: int = 5) -> None:
        self._port = port
        self.timeout = timeout
        self.attempts = attempts
        self.current: mt.Transfer | None = None

    def on_message(self, msg: Any) -> None:
        """A mission-protocol message from the autopilot, for the running transfer."""
        if self.current is not None:
            self.current.on_message(msg, self._port.now)

    def upload(
        self, items: list[mt.Item], *, mission_type: int = mt.MISSION, numbered_from: int = 0
    ) -> Generator[float, None, mt.Upload]:
        """Upload ``items`` (``numbered_from``: see :class:`~.mission_transfer.Upload`)."""

        def make(target: tuple[int, int], now: float) -> mt.Upload:
            return mt.Upload(
                items, target, now, numbered_from=numbered_from, **self._args(mission_type)
            )

        return (yield from self.run(make))

    def download(self, mission_type: int = mt.MISSION) -> Generator[float, None, mt.Download]:
        """Download the autopilot's list of ``mission_type``."""
        return (yield from self.run(lambda t, now: mt.Download(t, now, **self._args(mission_type))))

    def clear(self, mission_type: int = mt.MISSION) -> Generator[float, None, mt.Clear]:
        """Clear the autopilot's list of ``mission_type``."""
        return (yield from self.run(lambda t, now: mt.Clear(t, now, **self._args(mission_type))))

    def run(self, make: Callable[[tuple[int, int], float], T]) -> Generator[float, None, T]:
        """Wait for the turn, then run ``make(target, now)`` to its end; the machine ended."""
        port = self._port
        while self.current is not None and not self.current.done:
            yield port.now + WAIT_S
        transfer = make(port.target(), port.now)
        self.current = transfer
        try:
            while True:
                for message in transfer.due(port.now):
                    port.send(message)
                if transfer.done:
                    return transfer
                yield transfer.wake_at()
        finally:
            self.current = None

    def _args(self, mission_type: int) -> dict[str, Any]:
        return {"mission_type": mission_type, "timeout": self.timeout, "attempts": self.attempts}
