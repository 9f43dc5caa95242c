"""A one-slot mailbox that keeps only the newest item: the newest-frame policy.

Writers (the Zenoh callback) replace the item; the reader takes the newest one together with
its sequence number, atomically, so it knows exactly how many it skipped.
"""

from __future__ import annotations

import threading
import time
from typing import Generic, TypeVar

T = TypeVar("T")


class NewestSlot(Generic[T]):
    """Thread-safe holder of the newest item and a count of items put."""

    def __init__(self) -> None:
        self._cond = threading.Condition()
        self._item: T | None = None
        self.count = 0

    def put(self, item: T) -> None:
        """Replace the held item (an unread older one is dropped)."""
        with self._cond:
            self._item = item
            self.count += 1
            self._cond.notify_all()

    def take(self, timeout: float, newer_than: int) -> tuple[int, T] | None:
        """Wait up to ``timeout`` s for an item whose number is above ``newer_than``.

        Returns:
            (its number, the item), or None on timeout. Numbers start at 1.
        """
        deadline = time.monotonic() + timeout
        with self._cond:
            while self.count <= newer_than:
                remaining = deadline - time.monotonic()
                if remaining <= 0:
                    return None
                self._cond.wait(remaining)
            return self.count, self._item  # type: ignore[return-value]
