"""The teleop dead-man (pure, time injected).

A page sends velocity commands at a steady rate while a stick, a key or a gamepad is held.
When they stop coming (released, tab hidden, connection lost, browser crashed) for longer than
``timeout``, the drone must stop: :meth:`DeadMan.expired` says so once, and the station then
replaces the velocity command by a position hold where the drone is. If the station itself
dies, the bridge's setpoint expiry does the rest (hover, then land).
"""

from __future__ import annotations


class DeadMan:
    """Renewal watch of one drone's velocity teleop.

    Args:
        timeout: seconds without a renewal before the command expires.
    """

    def __init__(self, timeout: float) -> None:
        self.timeout = timeout
        self._renewed_at: float | None = None
        self.owner: object = None

    @property
    def active(self) -> bool:
        """Whether a velocity command is in force."""
        return self._renewed_at is not None

    def renew(self, now: float, owner: object = None) -> None:
        """A fresh velocity command arrived at ``now`` (s, monotonic) from ``owner``."""
        self._renewed_at = now
        self.owner = owner

    def release(self) -> bool:
        """The page let go on purpose; True if a command was in force (it must be stopped)."""
        was = self.active
        self._renewed_at = None
        self.owner = None
        return was

    def expired(self, now: float) -> bool:
        """True once when the command was not renewed within ``timeout`` (then released)."""
        if self._renewed_at is not None and now - self._renewed_at > self.timeout:
            self.release()
            return True
        return False
