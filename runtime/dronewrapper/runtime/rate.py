"""Loop pacing: a rate keeper that sleeps to the next tick and reports lag."""

from __future__ import annotations

import threading

from dronewrapper.runtime.clock import REAL, Clock


class Ratekeeper:
    """Keeps a loop at ``hz`` ticks per second on ``clock`` (the node's; waits through it).

    ``sleep()`` waits for the next tick (returning early if ``stop`` is set) and returns False
    when the loop should end, so a loop reads ``while rate.sleep(): ...``. A tick that starts
    late is counted in ``lagged``; after a long stall the schedule restarts rather than
    bursting to catch up.
    """

    def __init__(
        self,
        hz: float,
        *,
        stop: threading.Event | None = None,
        clock: Clock = REAL,
    ) -> None:
        if not hz > 0:
            raise ValueError(f"rate must be > 0 Hz, got {hz}")
        self.period = 1.0 / hz
        self._stop = stop or threading.Event()
        self._clock = clock
        self._next = clock.monotonic() + self.period
        self.frame = 0
        self.lagged = 0
        self.remaining = 0.0

    def sleep(self) -> bool:
        """Sleep until the next tick; False if the loop should stop."""
        now = self._clock.monotonic()
        self.remaining = self._next - now
        if self.remaining > 0:
            if self._clock.wait(self._stop, self.remaining):
                return False
        else:
            self.lagged += 1
            if -self.remaining > self.period:  # a long stall: restart the schedule
                self._next = now
        self._next += self.period
        self.frame += 1
        return not self._stop.is_set()
