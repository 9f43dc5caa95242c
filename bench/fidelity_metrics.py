"""Step-response figures of a recorded trace (pure): delay, rise time, overshoot, settling time
and steady-state error, and the sim/real ratio of each.

A step from ``y0`` to ``target`` commanded at ``t_step``, the trace ``(t, y)`` after it until the
next command:
- delay: until the response first covers 10 % of the step (s);
- rise time: from 10 % to 90 % of the step (s);
- overshoot: the largest excursion beyond the target, in % of the step;
- settling time: from the command until the response stays within ``band`` of the step (s);
- steady-state error: target minus the mean of the last ``tail_s`` of the trace, in % of the step.
A figure the trace never reaches is NaN.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import asdict, dataclass


@dataclass(frozen=True)
class StepFigures:
    delay_s: float
    rise_s: float
    overshoot_pct: float
    settling_s: float
    steady_error_pct: float

    def as_dict(self) -> dict[str, float]:
        return asdict(self)


def _first_crossing(t: Sequence[float], f: Sequence[float], level: float) -> float:
    for i, value in enumerate(f):
        if value >= level:
            if i == 0:
                return t[0]
            f0, f1 = f[i - 1], value
            frac = (level - f0) / (f1 - f0) if f1 != f0 else 0.0
            return t[i - 1] + frac * (t[i] - t[i - 1])
    return math.nan


def step_figures(
    t: Sequence[float],
    y: Sequence[float],
    t_step: float,
    y0: float,
    target: float,
    *,
    band: float = 0.1,
    tail_s: float = 1.0,
) -> StepFigures:
    """The figures of the response ``y(t)`` to a step ``y0 -> target`` at ``t_step``."""
    span = target - y0
    if span == 0 or len(t) < 2:
        raise ValueError("a step needs a non-zero size and at least two samples")
    pairs = [(ti, (yi - y0) / span) for ti, yi in zip(t, y, strict=True) if ti >= t_step]
    if len(pairs) < 2:
        raise ValueError("no samples after the step")
    ts = [p[0] for p in pairs]
    f = [p[1] for p in pairs]  # the fraction of the step covered: 0 -> 1
    t10 = _first_crossing(ts, f, 0.1)
    t90 = _first_crossing(ts, f, 0.9)
    overshoot = max(0.0, max(f) - 1.0) * 100.0
    settled = math.nan
    for i in range(len(f) - 1, -1, -1):
        if abs(f[i] - 1.0) > band:
            settled = ts[i + 1] - t_step if i + 1 < len(ts) else math.nan
            break
    else:
        settled = 0.0
    tail = [fi for ti, fi in zip(ts, f, strict=True) if ti >= ts[-1] - tail_s]
    steady = (1.0 - sum(tail) / len(tail)) * 100.0
    return StepFigures(
        delay_s=t10 - t_step,
        rise_s=t90 - t10,
        overshoot_pct=overshoot,
        settling_s=settled,
        steady_error_pct=steady,
    )


def ratio(ours: float, real: float) -> float:
    """ours / real; NaN when either is NaN or the real one is zero."""
    if not (math.isfinite(ours) and math.isfinite(real)) or real == 0:
        return math.nan
    return ours / real


def within(r: float, low: float = 0.8, high: float = 1.25) -> bool:
    return math.isfinite(r) and low <= r <= high
