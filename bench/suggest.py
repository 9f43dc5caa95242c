"""Detector settings that meet a glass-to-setpoint latency target (pure: figures in, advice out).

The model of one frame's latency, from what ``bench.quick`` measured on this computer:

    latency = render/capture + middleware + wait for the detector + detect

Perception always takes the newest frame as soon as it is free (the runtime's ``Latest``),
detecting on at most ``max_rate_hz`` of them a second, so frames never queue: a detector with
time to spare (``fps`` x detect time well under 1) takes each frame it uses on arrival, and only
a slow
detection (p99) running past the next frame it wants delays that one; a detector kept busy all
the time makes the newest frame wait for the run in progress, half a detection on average (a
whole one at worst). So p50 ~ render + middleware p50 + detect p50 + average wait and p99 ~
render + middleware p99 + detect p99 + worst wait.

The detector's rate is bounded by the CPU it may use (``cpu_budget``: cores, e.g. 0.5 = half of
one core, so the rest of the graph keeps its share) and by the camera's rate, and is never
suggested below ``min_fps`` (the tracker coasts between detections; below a few per second it
loses people who cross).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

SATURATED = 0.9
"""fps x detect time above this = the detector is busy all the time (frames wait for it)."""


@dataclass(frozen=True)
class DetectorSpeed:
    """The detector's time per frame at one network input size (s)."""

    input_size: int
    p50_s: float
    p99_s: float


@dataclass(frozen=True)
class Estimate:
    """Estimated latency (ms) and CPU of one setting."""

    input_size: int
    fps: float
    p50_ms: float
    p99_ms: float
    cpu_cores: float
    saturated: bool


@dataclass(frozen=True)
class Suggestion:
    """The setting to use, whether it meets the target, and why (one line)."""

    best: Estimate
    meets_target: bool
    reason: str
    candidates: tuple[Estimate, ...]


def estimate(
    speed: DetectorSpeed,
    fps: float,
    *,
    render_s: float,
    middleware_p50_s: float,
    middleware_p99_s: float,
    camera_fps: float,
) -> Estimate:
    """Latency and CPU of running the detector at ``fps`` (see the module's model)."""
    if not (fps > 0 and camera_fps > 0):
        raise ValueError("fps and camera_fps must be positive")
    fps = min(fps, camera_fps, 1.0 / speed.p50_s)
    busy = fps * speed.p50_s
    saturated = busy >= SATURATED
    if saturated:
        wait_avg, wait_worst = speed.p50_s / 2, speed.p99_s
    else:
        wait_avg, wait_worst = 0.0, max(0.0, speed.p99_s - 1.0 / fps)
    p50 = render_s + middleware_p50_s + speed.p50_s + wait_avg
    p99 = render_s + middleware_p99_s + speed.p99_s + wait_worst
    return Estimate(speed.input_size, fps, p50 * 1e3, p99 * 1e3, busy, saturated)


def suggest(
    target_ms: float,
    speeds: Sequence[DetectorSpeed],
    *,
    render_s: float,
    middleware_p50_s: float,
    middleware_p99_s: float,
    camera_fps: float = 30.0,
    cpu_budget: float = 1.0,
    min_fps: float = 5.0,
) -> Suggestion:
    """The largest input size (best detection) whose p50 estimate meets ``target_ms``, at the
    highest rate the CPU budget allows; else the fastest setting, saying by how much it misses.

    Raises:
        ValueError: no speeds, or a figure that is not finite and positive where it must be.
    """
    if not speeds:
        raise ValueError("no detector speeds measured")
    for name, value in (("target_ms", target_ms), ("camera_fps", camera_fps),
                        ("cpu_budget", cpu_budget), ("min_fps", min_fps)):  # fmt: skip
        if not (math.isfinite(value) and value > 0):
            raise ValueError(f"{name} must be finite and positive, got {value}")
    for speed in speeds:
        if not (math.isfinite(speed.p50_s) and speed.p50_s > 0 and speed.p99_s >= speed.p50_s):
            raise ValueError(f"bad detector speed {speed}")
    candidates = []
    for speed in sorted(speeds, key=lambda s: -s.input_size):
        fps = max(min_fps, min(camera_fps, math.floor(cpu_budget / speed.p50_s)))
        candidates.append(
            estimate(
                speed,
                fps,
                render_s=render_s,
                middleware_p50_s=middleware_p50_s,
                middleware_p99_s=middleware_p99_s,
                camera_fps=camera_fps,
            )
        )
    for cand in candidates:
        if cand.p50_ms <= target_ms:
            over = " (more CPU than the budget: min_fps)" if cand.cpu_cores > cpu_budget else ""
            return Suggestion(
                cand,
                True,
                f"input {cand.input_size} px at {cand.fps:.0f} fps: about {cand.p50_ms:.0f} ms "
                f"p50 / {cand.p99_ms:.0f} ms p99, {cand.cpu_cores:.2f} of a core{over}",
                tuple(candidates),
            )
    fastest = min(candidates, key=lambda c: c.p50_ms)
    return Suggestion(
        fastest,
        False,
        f"no setting meets {target_ms:.0f} ms here: the fastest, input {fastest.input_size} px "
        f"at {fastest.fps:.0f} fps, gives about {fastest.p50_ms:.0f} ms p50 (a GPU provider, a "
        f"smaller model or input, or a faster computer is needed)",
        tuple(candidates),
    )
