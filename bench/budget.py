"""The latency budget of a follow graph, stage by stage (pure: times in, figures out).

One camera frame's journey, every time in seconds on this machine's wall clock (the frame's
header stamp is ``time.time()`` when the simulator starts rendering it):

    stamp -> render -> publish (encode + put) -> transport -> perception queue wait -> decode
    -> compute (detect + track) -> publish + transport (Detections) -> controller + SDK +
    transport (setpoint) -> bridge + MAVLink out

``FrameTimes`` holds what a probe saw of one frame (arrival times at a subscriber in another
process, the timing fields perception puts in its Detections, the datagram leaving the bridge);
``stages`` splits it. Render and publish are not visible from outside the simulator, so they
come from the same scene rendered and encoded in the benchmark's process (``in_process``).
The middleware's share is everything but render and compute.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Stage:
    key: str
    label: str
    middleware: bool


STAGES: tuple[Stage, ...] = (
    Stage("render", "render / capture", False),
    Stage("publish_image", "publish frame (encode + copy to SHM)", True),
    Stage("transport_image", "transport frame (+ simulator waits)", True),
    Stage("queue", "perception queue wait", True),
    Stage("decode", "decode frame", True),
    Stage("compute", "compute (detect + track)", False),
    Stage("publish_detections", "publish + transport Detections", True),
    Stage("controller", "controller + SDK + transport setpoint", True),
    Stage("bridge", "bridge + MAVLink out", True),
)
STAGE_KEYS = tuple(s.key for s in STAGES)
MIDDLEWARE_KEYS = tuple(s.key for s in STAGES if s.middleware)


@dataclass(frozen=True)
class FrameTimes:
    """What was seen of one frame (s; absolute times are ``time.time()``).

    Attributes:
        stamp: the frame's capture stamp (render start).
        image_arrival: the frame reached perception (Detections.receive_time).
        detections_arrival: its Detections reached the probe.
        processing: Detections.processing_time (decode + detect + track).
        queue: Detections.queue_time (arrival at perception -> processing starts); NaN if
            perception does not report it.
        decode: Detections.decode_time; NaN if not reported.
        setpoint_arrival: the first velocity setpoint carrying the frame's stamp reached the
            probe.
        mavlink_out: its SET_POSITION_TARGET_LOCAL_NED datagram left the bridge; NaN if not
            seen.
    """

    stamp: float
    image_arrival: float
    detections_arrival: float
    processing: float
    queue: float
    decode: float
    setpoint_arrival: float
    mavlink_out: float = math.nan


def stages(frame: FrameTimes, render_s: float, publish_s: float) -> dict[str, float]:
    """Split one frame into the stages of :data:`STAGES` (s), plus ``total`` (stamp -> the
    last time seen: MAVLink out, else the setpoint) and ``middleware`` (total - render -
    compute).

    ``render_s`` and ``publish_s`` are the in-process figures for this scene (not visible from
    outside the simulator); the frame's transport is what remains of stamp -> arrival.
    A stage whose times are missing (NaN) is NaN and is left out of the middleware sum.
    """
    queue = frame.queue if math.isfinite(frame.queue) else 0.0
    decode = frame.decode if math.isfinite(frame.decode) else 0.0
    compute = frame.processing - decode
    out = {
        "render": render_s,
        "publish_image": publish_s,
        "transport_image": frame.image_arrival - frame.stamp - render_s - publish_s,
        "queue": frame.queue,
        "decode": frame.decode,
        "compute": compute,
        "publish_detections": frame.detections_arrival
        - frame.image_arrival
        - queue
        - frame.processing,
        "controller": frame.setpoint_arrival - frame.detections_arrival,
        "bridge": frame.mavlink_out - frame.setpoint_arrival,
    }
    end = frame.mavlink_out if math.isfinite(frame.mavlink_out) else frame.setpoint_arrival
    out["total"] = end - frame.stamp
    out["middleware"] = out["total"] - render_s - compute
    return out


def summarise(per_frame: Iterable[Mapping[str, float]]) -> dict[str, dict[str, float]]:
    """p50/p99 (ms) and count of each stage over frames (NaNs skipped)."""
    frames = list(per_frame)
    keys = [*STAGE_KEYS, "total", "middleware"]
    out: dict[str, dict[str, float]] = {}
    for key in keys:
        values = np.array([f[key] for f in frames if key in f], dtype=float)
        values = values[np.isfinite(values)] * 1e3
        if values.size == 0:
            out[key] = {"n": 0, "p50_ms": math.nan, "p99_ms": math.nan}
            continue
        out[key] = {
            "n": int(values.size),
            "p50_ms": float(np.percentile(values, 50)),
            "p99_ms": float(np.percentile(values, 99)),
        }
    return out


def budget_rows(summary: Mapping[str, Mapping[str, float]]) -> list[list[object]]:
    """Table rows: stage, counted in the middleware share (yes/no), p50 ms, p99 ms."""
    rows: list[list[object]] = [
        [s.label, "yes" if s.middleware else "no", summary[s.key]["p50_ms"],
         summary[s.key]["p99_ms"]]
        for s in STAGES
    ]  # fmt: skip
    rows.append(["glass -> MAVLink out (total)", "", summary["total"]["p50_ms"],
                 summary["total"]["p99_ms"]])  # fmt: skip
    rows.append(["middleware share (total - render - compute)", "",
                 summary["middleware"]["p50_ms"], summary["middleware"]["p99_ms"]])  # fmt: skip
    return rows


@dataclass(frozen=True)
class Growth:
    """A figure in the first window of a run against the last one (ms)."""

    first_p50_ms: float
    last_p50_ms: float
    first_p99_ms: float
    last_p99_ms: float
    first_n: int
    last_n: int

    @property
    def p50_change_ms(self) -> float:
        return self.last_p50_ms - self.first_p50_ms


def growth(times: Sequence[float], values_s: Sequence[float], window_s: float = 60.0) -> Growth:
    """p50/p99 of ``values_s`` in the first and in the last ``window_s`` of the run.

    ``times`` are when each value was taken (any clock); NaN values are skipped.
    """
    if len(times) != len(values_s):
        raise ValueError("times and values_s must have the same length")
    if window_s <= 0:
        raise ValueError("window_s must be positive")
    t = np.asarray(times, dtype=float)
    v = np.asarray(values_s, dtype=float) * 1e3
    keep = np.isfinite(t) & np.isfinite(v)
    t, v = t[keep], v[keep]
    if t.size == 0:
        return Growth(math.nan, math.nan, math.nan, math.nan, 0, 0)
    first = v[t <= t.min() + window_s]
    last = v[t >= t.max() - window_s]
    return Growth(
        first_p50_ms=float(np.percentile(first, 50)),
        last_p50_ms=float(np.percentile(last, 50)),
        first_p99_ms=float(np.percentile(first, 99)),
        last_p99_ms=float(np.percentile(last, 99)),
        first_n=int(first.size),
        last_n=int(last.size),
    )
