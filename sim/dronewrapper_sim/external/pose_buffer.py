"""The autopilot's recent truth on the wall clock, and the vehicle's pose at any instant.

Each truth sample gets a wall-clock time: the autopilot's own time plus an offset learnt as the
smallest (arrival - autopilot time) seen over the last ``window_s`` (a sample delayed by the
machine arrives late, never early), or its arrival time when the message carries no time or a
time that does not advance. The
pose at an instant ``t`` is interpolated between the two samples around ``t`` when ``t`` lies
inside the samples received; past the newest sample it is extrapolated from it with its own
velocity and yaw rate, for at most ``max_extrapolation_s``, and held beyond. A camera frame
captured now is therefore extrapolated by at most one truth period (40 ms at PX4 SIH's 25 Hz);
each answer says how old the newest truth was at ``t`` (its age). Pure: time is passed in.
"""

from __future__ import annotations

import bisect
import math
from collections import deque
from dataclasses import dataclass

from dronewrapper.rotations import wrap_pi
from dronewrapper_sim.external.alignment import LocalTruth

MAX_SAMPLES = 256  # about 10 s at 25 Hz, 5 s at 50 Hz


class ClockMap:
    """Maps an autopilot's clock to the wall clock (see module doc)."""

    def __init__(self, window_s: float = 2.0) -> None:
        self.window_s = window_s
        self._offsets: deque[tuple[float, float]] = deque()  # (arrival, arrival - autopilot t)
        self._autopilot_last: float | None = None

    def wall_time(self, autopilot_s: float | None, arrival_s: float) -> float:
        """The wall-clock time of a sample stamped ``autopilot_s`` that arrived at
        ``arrival_s``; the arrival itself when there is no stamp."""
        if autopilot_s is None:
            return arrival_s
        last = self._autopilot_last
        if last is not None and autopilot_s < last - 1.0:
            self._offsets.clear()  # the autopilot restarted: its clock began again
        elif last is not None and autopilot_s <= last:
            return arrival_s  # a clock that stands still says nothing about time
        self._autopilot_last = autopilot_s
        offset = arrival_s - autopilot_s
        while self._offsets and self._offsets[-1][1] >= offset:
            self._offsets.pop()  # a monotonic deque: the front is the window's minimum
        self._offsets.append((arrival_s, offset))
        while self._offsets[0][0] < arrival_s - self.window_s:
            self._offsets.popleft()
        return autopilot_s + self._offsets[0][1]


@dataclass(frozen=True)
class TimedPose:
    """A truth sample in the scenario's frame at wall-clock time ``t`` (s)."""

    t: float
    truth: LocalTruth


@dataclass(frozen=True)
class PoseAt:
    """The vehicle's pose at ``t``: position ENU (m), roll/pitch/yaw (rad), the newest truth's
    age at ``t`` (s; negative when ``t`` lies before it), and whether it was extrapolated."""

    t: float
    position: tuple[float, float, float]
    rpy: tuple[float, float, float]
    age_s: float
    extrapolated: bool


def _lerp(a: tuple[float, ...], b: tuple[float, ...], f: float) -> tuple[float, ...]:
    return tuple(x + (y - x) * f for x, y in zip(a, b, strict=True))


def _lerp_angles(a: tuple[float, ...], b: tuple[float, ...], f: float) -> tuple[float, ...]:
    return tuple(wrap_pi(x + wrap_pi(y - x) * f) for x, y in zip(a, b, strict=True))


class PoseBuffer:
    """The last truth samples in time order, and the pose at any instant (see module doc)."""

    def __init__(self, max_extrapolation_s: float = 0.1) -> None:
        self.max_extrapolation_s = max_extrapolation_s
        self._times: deque[float] = deque(maxlen=MAX_SAMPLES)
        self._poses: deque[TimedPose] = deque(maxlen=MAX_SAMPLES)

    def __len__(self) -> int:
        return len(self._poses)

    @property
    def newest(self) -> TimedPose | None:
        return self._poses[-1] if self._poses else None

    def add(self, pose: TimedPose) -> bool:
        """Keep ``pose``; a sample not newer than the newest is dropped (False)."""
        if self._poses and pose.t <= self._poses[-1].t:
            return False
        self._times.append(pose.t)
        self._poses.append(pose)
        return True

    def at(self, t: float) -> PoseAt | None:
        """The pose at wall-clock ``t`` (None before any sample)."""
        if not self._poses:
            return None
        newest = self._poses[-1]
        if t >= newest.t:
            return self._extrapolate(newest, t)
        i = bisect.bisect_right(self._times, t)
        if i == 0:  # older than everything kept: the oldest sample as it is
            oldest = self._poses[0].truth
            return PoseAt(t, oldest.position, oldest.rpy, t - newest.t, False)
        before, after = self._poses[i - 1], self._poses[i]
        f = (t - before.t) / (after.t - before.t)
        position = _lerp(before.truth.position, after.truth.position, f)
        rpy = _lerp_angles(before.truth.rpy, after.truth.rpy, f)
        return PoseAt(t, position, rpy, t - newest.t, False)  # type: ignore[arg-type]

    def _extrapolate(self, newest: TimedPose, t: float) -> PoseAt:
        dt = min(t - newest.t, self.max_extrapolation_s)
        s = newest.truth
        position = tuple(p + v * dt for p, v in zip(s.position, s.velocity, strict=True))
        roll, pitch, yaw = s.rpy
        rpy = (roll, pitch, wrap_pi(yaw + s.yaw_rate * dt))
        return PoseAt(t, position, rpy, t - newest.t, dt > 0.0)  # type: ignore[arg-type]


class AgeStats:
    """Ages (s) of the poses the camera frames were rendered from, since the last report."""

    def __init__(self) -> None:
        self.frames = 0
        self._ages: list[float] = []
        self._extrapolated = 0

    def add(self, pose: PoseAt) -> None:
        self.frames += 1
        self._ages.append(pose.age_s)
        self._extrapolated += pose.extrapolated

    def report(self) -> tuple[int, float, float, float, float]:
        """(frames, mean, p95, max age s, extrapolated share) since the last report; resets."""
        ages = sorted(self._ages)
        n = len(ages)
        extrapolated = self._extrapolated
        self._ages, self._extrapolated = [], 0
        if n == 0:
            return 0, math.nan, math.nan, math.nan, math.nan
        p95 = ages[min(n - 1, math.ceil(0.95 * n) - 1)]
        return n, sum(ages) / n, p95, ages[-1], extrapolated / n
