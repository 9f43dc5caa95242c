"""Detect at a chosen rate: which camera frames to process, judged by their stamps.

Pure: the decision uses the frames' own stamps (camera time, s), so it does not depend on how
loaded the machine is or on when the frames arrive.
"""

from __future__ import annotations

import math

SLACK = 0.1
"""Share of the period a frame may come early and still be taken (camera stamps jitter)."""


class FrameRateCap:
    """Admits frames at most ``max_rate_hz`` per second of camera time (0 = every frame).

    A frame is admitted when its stamp is at least ``(1 - SLACK) / max_rate_hz`` after the last
    admitted one; a stamp that goes back (a restarted camera or simulator) starts over.
    """

    def __init__(self, max_rate_hz: float) -> None:
        if not (math.isfinite(max_rate_hz) and max_rate_hz >= 0.0):
            raise ValueError(f"max_rate_hz must be finite and >= 0, got {max_rate_hz!r}")
        self.min_interval_s = (1.0 - SLACK) / max_rate_hz if max_rate_hz > 0 else 0.0
        self._last: float | None = None

    def admit(self, stamp: float) -> bool:
        """Whether to process the frame stamped ``stamp`` (s); records it when admitted."""
        last = self._last
        if last is not None and last <= stamp < last + self.min_interval_s:
            return False
        self._last = stamp
        return True
