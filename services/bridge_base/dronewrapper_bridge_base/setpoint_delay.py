"""The late-setpoint rule: a setpoint held on the way (a cut link's buffered burst) never flies.

Every setpoint publication carries its send time on the publisher's clock (the attachment, see
:mod:`dronewrapper.runtime.caller`). A setpoint's lag is (arrival on the bridge's clock - send
time on the publisher's): the two clocks' offset plus the link's delay. The smallest recent lag
of a commander is its offset plus the link's usual delay, so a setpoint whose lag exceeds that
minimum by more than ``threshold_s`` has waited on the way and is refused. A late setpoint
means the link has just stalled, and what was queued behind it arrives in a burst, its tail
having waited but little: so the commander is obeyed again only with setpoints sent at least
``threshold_s`` after the late one arrived (on the commander's clock: that arrival minus the
smallest lag). The rule needs no synchronised clocks.

The minimum is taken over the last ``window_s`` seconds of the commander's stream, a silence
counting for at most ``MAX_GAP_S``: a cut link never empties it, so the burst after a long cut
is still judged against the lags from before the cut, and a commander whose clock stepped back
is obeyed again ``window_s`` after the step. Each commander's lags are its own (a new one
starts afresh; the ``MAX_COMMANDERS`` most recent are remembered); a setpoint without a send
time (an older publisher) is judged by the lease alone.
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass

DEFAULT_THRESHOLD_S = 0.3
"""How much later than a commander's smallest recent lag a setpoint may arrive (s)."""

DEFAULT_WINDOW_S = 10.0
"""How long a smallest lag is remembered (s of arrivals)."""

MAX_GAP_S = 1.0
"""The most a silence between two setpoints ages the window (s): a stream is >= 20 Hz."""

MAX_SAMPLES = 4096
"""Most lags kept per commander (a steadily growing lag keeps one per sample)."""

MAX_COMMANDERS = 16
"""Most commanders whose lags are remembered (the least recently heard is forgotten)."""


@dataclass(frozen=True)
class Verdict:
    """The rule's answer for one setpoint: ``late`` (refuse it), its ``lag`` and the
    ``excess`` over the commander's smallest recent lag (s; 0 when unknown)."""

    late: bool
    lag: float = 0.0
    excess: float = 0.0


class SetpointDelay:
    """Judges each setpoint's lag against its commander's smallest recent lag.

    Args:
        threshold_s: refuse a setpoint whose lag exceeds the minimum by more than this (s).
        window_s: how long (s of arrivals) a minimum is remembered.
    """

    def __init__(
        self, threshold_s: float = DEFAULT_THRESHOLD_S, window_s: float = DEFAULT_WINDOW_S
    ) -> None:
        if not (math.isfinite(threshold_s) and threshold_s > 0):
            raise ValueError(f"threshold_s must be finite and > 0, got {threshold_s!r}")
        if not (math.isfinite(window_s) and window_s > 0):
            raise ValueError(f"window_s must be finite and > 0, got {window_s!r}")
        self.threshold_s = threshold_s
        self.window_s = window_s
        self.refused = 0
        # per commander: (stream time, lag) with both increasing, front the minimum; and the
        # commander's stream time (s of arrivals, a silence counting MAX_GAP_S at most) with
        # its last arrival
        self._lags: dict[str, deque[tuple[float, float]]] = {}
        self._stream: dict[str, tuple[float, float]] = {}
        # per commander: when a late setpoint arrived, on the commander's clock, plus
        # threshold_s: what was sent before is refused (the burst queued behind it)
        self._queued_before: dict[str, float] = {}

    def min_lag(self, commander: str) -> float | None:
        """``commander``'s smallest recent lag (s), None before its first timed setpoint."""
        lags = self._lags.get(commander)
        return lags[0][1] if lags else None

    def judge(self, commander: str, sent: float | None, arrival: float) -> Verdict:
        """Judge a setpoint from ``commander`` sent at ``sent`` (its clock, s; None: not
        known) that arrived at ``arrival`` (ours, s), and remember its lag."""
        if sent is None or not math.isfinite(sent):
            return Verdict(late=False)
        lag = arrival - sent
        lags = self._lags.pop(commander, None)
        if lags is None:
            lags = deque()
            if len(self._lags) >= MAX_COMMANDERS:
                oldest = next(iter(self._lags))
                del self._stream[oldest], self._lags[oldest]
                self._queued_before.pop(oldest, None)
        self._lags[commander] = lags  # the most recently heard last
        elapsed, last = self._stream.get(commander, (0.0, arrival))
        elapsed += min(max(arrival - last, 0.0), MAX_GAP_S)
        self._stream[commander] = (elapsed, arrival)
        while lags and lags[0][0] < elapsed - self.window_s:
            lags.popleft()
            self._queued_before.pop(commander, None)  # judged against a forgotten lag
        excess = lag - lags[0][1] if lags else 0.0
        late = excess > self.threshold_s
        if late:
            self._queued_before[commander] = arrival - lags[0][1] + self.threshold_s
        elif sent < self._queued_before.get(commander, -math.inf):
            late = True  # queued behind a late one, or too soon after it
        while lags and lags[-1][1] >= lag:
            lags.pop()
        lags.append((elapsed, lag))
        if len(lags) > MAX_SAMPLES:
            lags.popleft()
        if late:
            self.refused += 1
        return Verdict(late=late, lag=lag, excess=max(excess, 0.0))
