"""How full the autopilot link is, from its byte counts (pure; time injected, monotonic s).

:class:`LinkLoad` turns the link's running byte counts into bytes a second each way over a
sliding window, and a serial line's load: the busier direction's rate over the line's
capacity (``baud / 10`` B/s each way; a line is full at 1.0). :class:`LoadAlarm` says, once,
when the load crosses the warning threshold, and once when it is back below it by a margin.
:class:`Reconnects` counts the times the link came back.
"""

from __future__ import annotations

import collections

WINDOW_S = 2.0
"""s of counts the rates are taken over."""
CLEAR_MARGIN = 0.1
"""The load must fall this far below the threshold before the alarm clears (no flapping)."""


class LinkLoad:
    """Bytes a second each way, and the load of a line of ``capacity`` B/s (0: no line)."""

    def __init__(self, capacity: float, window_s: float = WINDOW_S) -> None:
        self.capacity = capacity
        self.window_s = window_s
        self._samples: collections.deque[tuple[float, int, int]] = collections.deque()

    def add(self, now: float, received: int, sent: int) -> None:
        """The link's running totals of bytes received and sent at ``now``."""
        self._samples.append((now, received, sent))
        while len(self._samples) > 2 and now - self._samples[1][0] >= self.window_s:
            self._samples.popleft()

    def rates(self) -> tuple[float, float]:
        """(received, sent) bytes a second over the window; zeros before two samples."""
        if len(self._samples) < 2:
            return 0.0, 0.0
        (t0, rx0, tx0), (t1, rx1, tx1) = self._samples[0], self._samples[-1]
        if t1 <= t0:
            return 0.0, 0.0
        return max(0, rx1 - rx0) / (t1 - t0), max(0, tx1 - tx0) / (t1 - t0)

    def load(self) -> float:
        """The busier direction's share of the line (0 for a network link, 1.0 = full)."""
        if self.capacity <= 0:
            return 0.0
        return max(self.rates()) / self.capacity


class LoadAlarm:
    """A sentence when the load crosses ``threshold`` upward, and one when it has cleared."""

    def __init__(self, threshold: float) -> None:
        self.threshold = threshold
        self.raised = False

    def update(self, load: float, what: str) -> str | None:
        """The sentence to log for this load (``what`` describes the link), or None."""
        if not self.raised and load >= self.threshold:
            self.raised = True
            return (
                f"link {load * 100:.0f} % full ({what}): telemetry will be late and then lost; "
                "lower message_rates or raise the baud"
            )
        if self.raised and load < self.threshold - CLEAR_MARGIN:
            self.raised = False
            return f"link back to {load * 100:.0f} % ({what})"
        return None


class Reconnects:
    """Times the link came back: the device or socket reopened after an error, or heartbeats
    again after they had stopped (one event counted once when both happen)."""

    def __init__(self) -> None:
        self.count = 0
        self._opened = False
        self._was_connected = False  # heartbeats arrived at the last look
        self._lost = False  # they stopped after arriving, and have not come back

    def opened(self) -> None:
        """The link was opened (the first time is no reconnect)."""
        if self._opened:
            self.count += 1
            self._lost = False  # the heartbeats' return is this reconnect
        self._opened = True

    def heartbeat(self, connected: bool) -> None:
        """Whether heartbeats arrive now (looked at about once a second)."""
        if connected and self._lost:
            self.count += 1
        self._lost = (self._was_connected or self._lost) and not connected
        self._was_connected = connected
