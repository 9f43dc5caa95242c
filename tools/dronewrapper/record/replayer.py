"""A recording re-published on Zenoh with its original timing.

:class:`ReplayClock` maps recorded time to wall time (pure, time injected); :func:`replay`
publishes each recorded bus message on its key when its time comes, at ``rate`` times the
original speed, optionally looping and publishing the recorded time on ``clock``.
"""

from __future__ import annotations

import threading
import time
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field
from pathlib import Path

import zenoh

from dronewrapper.msgs import codec, registry
from dronewrapper.msgs.std import Header
from dronewrapper.record.reader import BusMessage, read_bus
from dronewrapper.runtime.node import encoding_for

CLOCK_PERIOD_S = 0.01
"""Longest gap between two clock messages during a replay (recorded s)."""


@dataclass
class ReplayClock:
    """Recorded time -> wall time: ``wall0 + (recorded - recorded0) / rate`` (s)."""

    recorded0: float
    wall0: float
    rate: float = 1.0

    def __post_init__(self) -> None:
        if not (self.rate > 0 and self.rate < 1e6):
            raise ValueError(f"replay rate must be > 0, got {self.rate}")

    def wall_time(self, recorded: float) -> float:
        return self.wall0 + (recorded - self.recorded0) / self.rate

    def recorded_time(self, wall: float) -> float:
        return self.recorded0 + (wall - self.wall0) * self.rate


@dataclass
class ReplayStats:
    """What a replay did; ``lateness`` holds, per message, wall time after its due time (s)."""

    published: int = 0
    loops: int = 0
    lateness: list[float] = field(default_factory=list)


def replay(
    session: zenoh.Session,
    path: str | Path,
    stop: threading.Event,
    *,
    rate: float = 1.0,
    loop: bool = False,
    start_s: float = 0.0,
    keys: Iterable[str] | None = None,
    clock: bool = False,
    now: Callable[[], float] = time.monotonic,
) -> ReplayStats:
    """Publish the recording at ``path`` until its end (or ``stop``; forever with ``loop``).

    Args:
        rate: speed factor (2 = twice as fast).
        start_s: skip the first ``start_s`` seconds of the recording.
        keys: key expressions to replay (default all).
        clock: publish the recorded time on ``clock`` (:data:`registry.CLOCK`).
    """
    if start_s < 0:
        raise ValueError(f"start must be >= 0 s, got {start_s}")
    keys = list(keys) if keys else None
    stats = ReplayStats()
    publishers: dict[str, zenoh.Publisher] = {}
    clock_pub = (
        session.declare_publisher(registry.CLOCK.key(), encoding=encoding_for(registry.CLOCK.type))
        if clock
        else None
    )
    first = next(iter(read_bus(path)), None)
    if first is None:
        return stats
    start_ns = first.log_time_ns + int(start_s * 1e9)

    def publisher(msg: BusMessage) -> zenoh.Publisher:
        pub = publishers.get(msg.key)
        if pub is None:
            topic = msg.topic
            encoding = encoding_for(topic.type) if topic else zenoh.Encoding("application/msgpack")
            pub = session.declare_publisher(msg.key, encoding=encoding)
            publishers[msg.key] = pub
        return pub

    try:
        while not stop.is_set():
            timeline: ReplayClock | None = None
            last_clock = -1e18
            for msg in read_bus(path, keys, start_ns=start_ns):
                recorded = msg.log_time_ns / 1e9
                if timeline is None:
                    timeline = ReplayClock(recorded, now(), rate)
                due = timeline.wall_time(recorded)
                # sleep in small steps, publishing the clock meanwhile when asked
                while (wait := due - now()) > 0:
                    if clock_pub is not None:
                        t = min(recorded, timeline.recorded_time(now()))
                        if t - last_clock >= CLOCK_PERIOD_S:
                            clock_pub.put(codec.encode(Header(stamp=t, frame_id="replay")))
                            last_clock = t
                    if stop.wait(min(wait, CLOCK_PERIOD_S / rate if clock_pub else wait)):
                        return stats
                publisher(msg).put(msg.payload)
                stats.lateness.append(now() - due)
                stats.published += 1
            stats.loops += 1
            if not loop or timeline is None:
                break
    finally:
        for pub in publishers.values():
            pub.undeclare()
        if clock_pub is not None:
            clock_pub.undeclare()
    return stats
