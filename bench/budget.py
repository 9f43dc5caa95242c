"""The latency budget of a follow graph, stage by stage (pure: times in, figures out).

One camera frame's journey, every instant in seconds on this machine's wall clock
(``time.time()``, one clock for every process here; the frame's header stamp is taken when the
simulator starts rendering it):

    stamp -> render -> publish (encode + put) -> transport -> perception queue wait -> decode
    -> compute (detect + track) -> [Detections published] -> transport + controller + SDK
    -> [setpoint sent] -> transport + bridge -> [MAVLink datagram at the relay]

Each measured stage runs between two instants on the frame's own path, each taken where the
event happens: perception's ``receive_time`` and its durations (``queue_time``,
``processing_time``), the setpoint's send time (the ``sent`` attachment the SDK adds to every
setpoint, on the controller's clock) and the datagram's arrival at the relay between the bridge
and the simulator. An instant can only follow the one before it, so no measured stage is
negative; a frame whose instants are out of that order was wrongly joined (or the clock was
stepped) and :func:`stages` refuses it. A probe's arrival times (another subscriber, in another
process) are not on the path: they name which frame a setpoint answers and give the reference
figures, never a stage's end.

Render and publish are not visible from outside the simulator, so they are the same scene
rendered and encoded in the benchmark's process (in-process p50 estimates); the frame's
transport is what remains of stamp -> arrival at perception, and may be slightly negative when
the simulator renders faster than the estimate (the three rows sum right). The middleware's
share is everything but render and compute.
"""

from __future__ import annotations

import itertools
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
    Stage("controller", "publish Detections + transport + controller + SDK", True),
    Stage("bridge", "transport setpoint + bridge + MAVLink out", True),
)
STAGE_KEYS = tuple(s.key for s in STAGES)
MIDDLEWARE_KEYS = tuple(s.key for s in STAGES if s.middleware)
MEASURED_KEYS = ("queue", "decode", "compute", "controller", "bridge")  # between path instants
REFERENCE_KEYS = ("detections_to_subscriber",)  # figures beside the stages, not summed
MATCH_WINDOW_S = 0.100  # a setpoint's datagram leaves the bridge at most this long after sending


@dataclass(frozen=True)
class FrameTimes:
    """What was seen of one frame (s; absolute times are ``time.time()``).

    Attributes:
        stamp: the frame's capture stamp (render start, the simulator's clock).
        image_arrival: the frame reached perception (Detections.receive_time).
        detections_arrival: its Detections reached the probe (reference only).
        processing: Detections.processing_time (decode + detect + track).
        queue: Detections.queue_time (arrival at perception -> processing starts); NaN if
            perception does not report it.
        decode: Detections.decode_time; NaN if not reported.
        setpoint_arrival: the first velocity setpoint carrying the frame's stamp reached the
            probe (reference only: it names the frame).
        setpoint_sent: that setpoint's send time (its ``sent`` attachment, the controller's
            clock); NaN if it carried none.
        mavlink_out: its SET_POSITION_TARGET_LOCAL_NED datagram reached the relay; NaN if not
            seen.
    """

    stamp: float
    image_arrival: float
    detections_arrival: float
    processing: float
    queue: float
    decode: float
    setpoint_arrival: float
    setpoint_sent: float = math.nan
    mavlink_out: float = math.nan

    @property
    def detections_published(self) -> float:
        """When perception had its Detections ready to publish: arrival + queue + processing
        (a lower bound of the publication; its own durations, perception's clock)."""
        queue = self.queue if math.isfinite(self.queue) else 0.0
        return self.image_arrival + queue + self.processing


class OutOfOrder(ValueError):
    """A frame's path instants are not in the order its journey makes them."""


def path_instants(frame: FrameTimes) -> list[tuple[str, float]]:
    """The frame's instants on its own path, in journey order (missing ones left out)."""
    named = [
        ("stamp", frame.stamp),
        ("arrival at perception", frame.image_arrival),
        ("Detections published", frame.detections_published),
        ("setpoint sent", frame.setpoint_sent),
        ("MAVLink out", frame.mavlink_out),
    ]
    return [(name, t) for name, t in named if math.isfinite(t)]


def stages(frame: FrameTimes, render_s: float, publish_s: float) -> dict[str, float]:
    """Split one frame into the stages of :data:`STAGES` (s), plus ``total`` (stamp -> the
    last path instant seen: MAVLink out, else the setpoint's send) and ``middleware``
    (total - render - compute), and the reference figures of :data:`REFERENCE_KEYS`.

    ``render_s`` and ``publish_s`` are the in-process figures for this scene (not visible from
    outside the simulator); the frame's transport is what remains of stamp -> arrival.
    A stage whose times are missing (NaN) is NaN and is left out of the middleware sum.

    Raises:
        OutOfOrder: an instant of the frame's path precedes the one before it.
    """
    path = path_instants(frame)
    for (before, t0), (after, t1) in itertools.pairwise(path):
        if t1 < t0:
            raise OutOfOrder(f"{after} ({t1:.6f}) precedes {before} ({t0:.6f})")
    decode = frame.decode if math.isfinite(frame.decode) else 0.0
    compute = frame.processing - decode
    published = frame.detections_published
    out = {
        "render": render_s,
        "publish_image": publish_s,
        "transport_image": frame.image_arrival - frame.stamp - render_s - publish_s,
        "queue": frame.queue,
        "decode": frame.decode,
        "compute": compute,
        "controller": frame.setpoint_sent - published,
        "bridge": frame.mavlink_out - frame.setpoint_sent,
        "detections_to_subscriber": frame.detections_arrival - published,
    }
    end = path[-1][1]
    out["total"] = end - frame.stamp
    out["middleware"] = out["total"] - render_s - compute
    return out


def split_all(
    frames: Iterable[FrameTimes], render_s: float, publish_s: float
) -> tuple[list[dict[str, float]], list[FrameTimes], list[str]]:
    """:func:`stages` of every frame: (the stages of each frame kept, those frames, why each
    other one was left out: its path instants out of order)."""
    per_frame, kept, left_out = [], [], []
    for frame in frames:
        try:
            per_frame.append(stages(frame, render_s, publish_s))
        except OutOfOrder as exc:  # a wrong join, or a stepped clock: not a figure
            left_out.append(str(exc))
        else:
            kept.append(frame)
    return per_frame, kept, left_out


def first_datagram(
    sent: float,
    key: Sequence[float],
    datagrams: Sequence[tuple[float, Sequence[float]]],
    used: set[int],
    window_s: float = MATCH_WINDOW_S,
) -> float:
    """When the datagram a setpoint sent at ``sent`` became reached the relay: the first of
    ``datagrams`` ((arrival, key), sorted by arrival) not in ``used`` whose key matches
    ``key`` (float32 on the wire), arriving in [sent, sent + window_s]; its index is added to
    ``used``. NaN if none (or ``sent`` is unknown): a datagram can never precede its send."""
    if not math.isfinite(sent):
        return math.nan
    for i, (t, datagram_key) in enumerate(datagrams):
        if t < sent or i in used:
            continue
        if t > sent + window_s:
            break
        if np.allclose(datagram_key, key, rtol=1e-5, atol=1e-5):
            used.add(i)
            return t
    return math.nan


@dataclass(frozen=True)
class SetpointPath:
    """One frame's setpoint from glass to the autopilot (wall-clock s): the frame's capture
    ``stamp``, the setpoint's ``sent`` time at the controller, and ``out``: when the frame it
    became reached the autopilot (NaN when none matched)."""

    stamp: float
    sent: float
    out: float

    @property
    def glass_to_out(self) -> float:
        return self.out - self.stamp

    @property
    def sent_to_out(self) -> float:
        """The setpoint's own path: transport, bridge and the link to the autopilot."""
        return self.out - self.sent


def setpoint_paths(
    setpoints: Mapping[float, tuple[float, Sequence[float]]],
    frames: Sequence[tuple[float, Sequence[float]]],
    window_s: float = MATCH_WINDOW_S,
) -> list[SetpointPath]:
    """Each setpoint (frame stamp -> (sent, key)) joined to the first not yet used of
    ``frames`` ((arrival at the autopilot, key), sorted by arrival) with its values, within
    ``window_s`` of its send (:func:`first_datagram`), in stamp order."""
    used: set[int] = set()
    ordered = sorted(frames, key=lambda frame: frame[0])
    return [
        SetpointPath(stamp, sent, first_datagram(sent, key, ordered, used, window_s))
        for stamp, (sent, key) in sorted(setpoints.items())
    ]


def summarise(per_frame: Iterable[Mapping[str, float]]) -> dict[str, dict[str, float]]:
    """p50/p99 (ms) and count of each stage over frames (NaNs skipped)."""
    frames = list(per_frame)
    keys = [*STAGE_KEYS, "total", "middleware", *REFERENCE_KEYS]
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
