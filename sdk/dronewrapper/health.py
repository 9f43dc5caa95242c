"""Stream health against the registry: rate, age and clock skew of what arrives (pure).

A subscriber records, for each key, when samples arrived (monotonic seconds) and how far the
sender's ``header.stamp`` was behind this computer's clock at arrival (wall seconds). From those
this module judges each stream against the rate the registry declares for its topic, so
``dronewrapper doctor`` and the SDK say "pose 3 Hz, expected >= 30 Hz" instead of a user
guessing.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Sequence
from dataclasses import dataclass, field

OK, WARN, FAIL = "ok", "warn", "fail"

RATE_SLACK = 0.7
"""A stream is slow below this fraction of its registry rate (jitter and short windows)."""
MIN_ARRIVALS_FOR_RATE = 5
"""Fewer arrivals than this measure no rate worth judging (``echo --count 2`` sees one or two
gaps, and one late frame halves the estimate)."""
CLOCK_SKEW_WARN_S = 0.25
"""Stamps further than this from our clock point at unsynchronised clocks (or a slow link)."""


STALE_PERIODS = 5.0
"""A stream is stale after this many of its registry periods without a sample..."""
STALE_FLOOR_S = 0.5
"""...but never sooner than this (s), so jitter on a fast stream is not staleness."""


def stale_after(rate_hz: float) -> float:
    """Seconds after which a value of a stream with this registry rate is stale: the one
    freshness rule (the SDK's getters, ``dronewrapper echo`` and ``doctor``). Five missed
    periods, but never less than half a second; 0 Hz (event streams) never goes stale -> inf."""
    return max(STALE_FLOOR_S, STALE_PERIODS / rate_hz) if rate_hz > 0 else float("inf")


def is_stale(rate_hz: float, age_s: float) -> bool:
    """Whether a value ``age_s`` seconds old on a stream of registry rate ``rate_hz`` is stale."""
    return age_s > stale_after(rate_hz)


@dataclass
class StreamLog:
    """What arrived on one key while listening: arrival times, stamp skews, payload bytes."""

    arrivals: list[float] = field(default_factory=list)
    skews: list[float] = field(default_factory=list)
    bytes: int = 0

    def add(self, arrival: float, skew: float | None, size: int) -> None:
        """Record one sample: ``arrival`` (monotonic s), ``skew`` = our wall clock minus the
        sample's ``header.stamp`` (s, None without a stamp), ``size`` in bytes."""
        self.arrivals.append(arrival)
        if skew is not None:
            self.skews.append(skew)
        self.bytes += size


@dataclass(frozen=True)
class StreamHealth:
    """The verdict on one stream."""

    key: str
    rate_hz: float
    """Measured rate: 1 / median interval between arrivals (0 with fewer than 2 samples)."""
    expected_hz: float
    """The registry's nominal rate (0: event-driven, no rate expected)."""
    age_s: float
    """Seconds since the newest sample, at the end of listening."""
    skew_s: float | None
    """Median of (our wall clock - header.stamp) at arrival; None if unstamped."""
    verdict: str
    note: str


def median_rate(arrivals: Sequence[float]) -> float:
    """1 / the median gap between consecutive arrivals; 0 with fewer than two (Hz)."""
    import statistics  # here: importing the SDK loads no statistics (nor random, fractions)

    gaps = [b - a for a, b in itertools.pairwise(arrivals) if b > a]
    return 1.0 / statistics.median(gaps) if gaps else 0.0


def judge_stream(key: str, expected_hz: float, log: StreamLog, end: float) -> StreamHealth:
    """Judge one stream heard until monotonic time ``end`` against its registry rate."""
    import statistics

    rate = median_rate(log.arrivals)
    age = end - log.arrivals[-1] if log.arrivals else float("inf")
    skew = statistics.median(log.skews) if log.skews else None
    verdict, notes = OK, []
    if expected_hz > 0:
        if not log.arrivals:
            verdict = FAIL
            notes.append(f"nothing arrived (expected >= {expected_hz:g} Hz)")
        elif len(log.arrivals) >= MIN_ARRIVALS_FOR_RATE and rate < RATE_SLACK * expected_hz:
            verdict = WARN
            notes.append(f"{rate:.1f} Hz, expected >= {expected_hz:g} Hz")
        elif is_stale(expected_hz, age):
            verdict = WARN
            notes.append(f"stopped {age:.1f} s ago (stale after {stale_after(expected_hz):g} s)")
        elif len(log.arrivals) < MIN_ARRIVALS_FOR_RATE:
            notes.append(f"{len(log.arrivals)} samples: too few to judge the rate")
    if skew is not None and abs(skew) > CLOCK_SKEW_WARN_S:
        verdict = WARN if verdict == OK else verdict
        notes.append(f"stamps {skew * 1000:+.0f} ms from this clock")
    return StreamHealth(key, rate, expected_hz, age, skew, verdict, "; ".join(notes))


def describe_stream(health: StreamHealth) -> str:
    """One line on a stream: measured rate and newest sample's age against the registry rate,
    and what is wrong if anything (``dronewrapper echo`` and ``doctor``)."""
    rate = f"{health.rate_hz:.1f} Hz" if health.rate_hz else "-"
    declared = f"declared {health.expected_hz:g} Hz" if health.expected_hz > 0 else "event-driven"
    age = f", newest {health.age_s:.2f} s old" if math.isfinite(health.age_s) else ""
    detail = f": {health.note}" if health.note else ""
    return f"{health.key}: {rate} ({declared}){age}{detail}"


def clock_advice(skews_s: Sequence[float]) -> tuple[str, str]:
    """(verdict, sentence) about the clocks of the senders, from the stamp skews of every stream.

    Positive skew = stamps in our past (a transport delay, or a sender's clock behind ours);
    negative = stamps in our future, which only a clock difference explains.
    """
    import statistics

    if not skews_s:
        return WARN, "no stamped message arrived, so the clocks could not be compared"
    skew = statistics.median(skews_s)
    if skew < -0.02:
        return WARN, (
            f"senders' stamps are {-skew * 1000:.0f} ms ahead of this computer's clock: "
            "synchronise the clocks (chrony or systemd-timesyncd on both machines)"
        )
    if skew > CLOCK_SKEW_WARN_S:
        return WARN, (
            f"messages arrive {skew * 1000:.0f} ms after their stamps: a clock difference or a "
            "congested link (check chrony, and use compressed images on Wi-Fi)"
        )
    return OK, f"stamps are {skew * 1000:.0f} ms behind this computer's clock"


RAW_CAMERA_MBIT_S = 640 * 480 * 3 * 30 * 8 / 1e6
"""One raw 640x480 bgr8 camera at 30 Hz, in Mbit/s (about 221)."""


def bandwidth_advice(mbit_s: float) -> tuple[str, str]:
    """(verdict, sentence) about a measured link rate to the router (Mbit/s)."""
    if mbit_s <= 0:
        return FAIL, "the bandwidth probe did not come back through the router"
    if mbit_s < 2 * RAW_CAMERA_MBIT_S:
        return WARN, (
            f"{mbit_s:.0f} Mbit/s through the router: too little for raw camera frames "
            f"(~{RAW_CAMERA_MBIT_S:.0f} Mbit/s each); use DroneWrapper(compressed_images=True) or "
            "cameras=() on this link"
        )
    return OK, f"{mbit_s:.0f} Mbit/s through the router"
