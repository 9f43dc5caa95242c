"""Which refusals a bridge publishes to their commanders (pure, time injected).

Every refusal is told to its commander (:mod:`dronewrapper.msgs.refusal`), but a setpoint
stream refused for the same reason would repeat it at the stream's rate. :class:`RefusalThrottle`
publishes the first refusal of a kind at once and then, while identical ones keep coming, one
every ``period_s`` carrying how many it stands for. Two refusals are identical when their
commander, kind, input and limit agree (for a refusal naming no limit: its message with the
figures taken out), so a moving target refused for the same limit is still one stream.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass

from dronewrapper.msgs.refusal import REPEAT_PERIOD_S

MAX_KEYS = 64
"""Most refusal streams remembered (the least recently refused is forgotten)."""

_FIGURES = re.compile(r"[-+]?\d[\d.]*(?:e[-+]?\d+)?")


@dataclass
class _Stream:
    published_at: float  # monotonic s of the last publication
    held: int = 0  # refused since then, not yet published


class RefusalThrottle:
    """Says which refusals to publish now, and how many each stands for.

    Args:
        period_s: identical refusals are published at most this often after the first (s).
    """

    def __init__(self, period_s: float = REPEAT_PERIOD_S) -> None:
        if not (math.isfinite(period_s) and period_s > 0):
            raise ValueError(f"period_s must be finite and > 0, got {period_s!r}")
        self.period_s = period_s
        self.refused = 0  # every refusal seen
        self.published = 0  # the messages published for them
        self._streams: dict[tuple[str, ...], _Stream] = {}

    def admit(
        self, now: float, commander: str, kind: str, what: str, limit: str, message: str
    ) -> int:
        """A refusal at ``now`` (monotonic s): the count to publish it with, or 0 to hold it
        (an identical one was published less than ``period_s`` ago)."""
        self.refused += 1
        key = (commander, kind, what, limit or _FIGURES.sub("#", message))
        stream = self._streams.pop(key, None)
        if stream is None and len(self._streams) >= MAX_KEYS:
            del self._streams[next(iter(self._streams))]
        if stream is not None and now - stream.published_at < self.period_s:
            stream.held += 1
            self._streams[key] = stream  # the most recently refused last
            return 0
        count = 1 + (stream.held if stream is not None else 0)
        self._streams[key] = _Stream(published_at=now)
        self.published += 1
        return count
