"""The setpoint stream toward the autopilot: each setpoint crosses the link once (pure; time
injected, s).

The bridge forwards a commander's setpoint the moment it arrives. While that setpoint is fresh
(younger than ``setpoint_timeout``) the stream tick (``stream_rate_hz``) sends it again only
when nothing has gone out for ``period_s`` (the keep-alive, ``setpoint_keepalive_s``): the
app's stream paused. So the autopilot receives a setpoint at least every ``period_s`` plus one
tick (PX4 leaves OFFBOARD COM_OF_LOSS_T, 1 s, after the last one and enters it only on a > 2 Hz
stream), and, while fresh setpoints arrive more often than every ``period_s``, never the same
one twice: the uplink carries the app's stream and nothing more. "The same" is identity
(``is``), not equality: a commander's new setpoint is always forwarded, even if equal to the
last.

What the bridge streams on its own account (a hold after a setpoint expired, its own hold,
a priming hold: the failsafe's, :mod:`dronewrapper_bridge_base.guided_failsafe`) goes out on
every tick, unless a setpoint went out less than ``min_gap_s`` ago (half a tick: one was just
forwarded).
"""

from __future__ import annotations

import math

STREAM_GAP_S = 0.5
"""s without a setpoint sent: the stream has stopped (a priming stream starts again)."""

MAX_PERIOD_S = 0.4
"""The longest keep-alive period (s): with a tick's lateness it stays under STREAM_GAP_S and
PX4's 2 Hz."""


class KeepAlive:
    """When the stream tick sends, and how long the bridge has streamed without a gap."""

    def __init__(self, period_s: float, min_gap_s: float) -> None:
        if not 0 < period_s <= MAX_PERIOD_S:
            raise ValueError(
                f"keep-alive period must be in (0, {MAX_PERIOD_S}] s, got {period_s!r}"
            )
        self.period_s = period_s
        self.min_gap_s = min_gap_s
        self._last: object | None = None
        self._last_at = -math.inf
        self._since = -math.inf

    def due(self, target: object, now: float, *, fresh: bool) -> bool:
        """True when the stream tick must send ``target`` at ``now``: a ``fresh`` commander's
        setpoint if it is not the one last sent or nothing has gone out for ``period_s``; the
        bridge's own target if nothing has gone out for ``min_gap_s``."""
        elapsed = now - self._last_at
        if not fresh:
            return elapsed >= self.min_gap_s
        return target is not self._last or elapsed >= self.period_s

    def sent(self, target: object, now: float) -> None:
        """``target`` went to the autopilot at ``now`` (forwarded or sent by the tick)."""
        if now - self._last_at > STREAM_GAP_S:
            self._since = now
        self._last, self._last_at = target, now

    def streamed_for(self, now: float) -> float:
        """Seconds setpoints have been sent without a gap longer than STREAM_GAP_S (0 if not
        now)."""
        if now - self._last_at > STREAM_GAP_S:
            return 0.0
        return now - self._since


__all__ = ["MAX_PERIOD_S", "STREAM_GAP_S", "KeepAlive"]
