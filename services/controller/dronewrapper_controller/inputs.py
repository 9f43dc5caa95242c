"""Which detections messages the controller may steer on (pure).

A Detections message is a network input: a buggy or hostile publisher can send NaN or infinite
stamps, sizes or boxes. The PIDs refuse non-finite input by raising, so one such message would
kill the controller (and the flight would lose its commander). Every message is checked here
first; a bad one is counted and dropped and the previous good one stays the newest.
"""

from __future__ import annotations

import math
from collections.abc import Callable

from dronewrapper.msgs.vision import Detections

MAX_IMAGE_SIDE = 100_000  # px: larger frame sizes are not a camera's
MAX_STAMP = 2**40  # s since the epoch (year ~36800): a bound that still rejects 1e300


def detections_problem(msg: Detections) -> str | None:
    """Why ``msg`` cannot be steered on (naming the field), or None when it is usable."""
    stamp = msg.header.stamp
    if not (math.isfinite(stamp) and 0.0 <= stamp <= MAX_STAMP):
        return f"header.stamp must be finite seconds since the epoch, got {stamp!r}"
    for name in ("image_width", "image_height"):
        side = getattr(msg, name)
        if not 0 <= side <= MAX_IMAGE_SIDE:
            return f"{name} must be within [0, {MAX_IMAGE_SIDE}] px, got {side}"
    if not math.isfinite(msg.processing_time):
        return f"processing_time must be finite, got {msg.processing_time!r}"
    for i, det in enumerate(msg.detections):
        box = det.bbox
        values = {
            "bbox.center.position.x": box.center.position.x,
            "bbox.center.position.y": box.center.position.y,
            "bbox.center.theta": box.center.theta,
            "bbox.size_x": box.size_x,
            "bbox.size_y": box.size_y,
            "circle_radius": det.circle_radius,
            "header.stamp": det.header.stamp,
        }
        for j, result in enumerate(det.results):
            values[f"results[{j}].hypothesis.score"] = result.hypothesis.score
        for name, value in values.items():
            if not math.isfinite(value):
                return f"detections[{i}].{name} must be finite, got {value!r}"
        for name in ("bbox.size_x", "bbox.size_y", "circle_radius"):
            if values[name] < 0:
                return f"detections[{i}].{name} must be >= 0, got {values[name]!r}"
    return None


class DetectionsGate:
    """Passes good Detections to ``accept``; counts, and reports through ``on_drop``, the rest.

    (A frame stamped before the last one used is harmless: the PIDs ignore dt <= 0.)
    """

    def __init__(
        self,
        accept: Callable[[Detections], None],
        on_drop: Callable[[int, str], None] | None = None,
    ) -> None:
        self.accept = accept
        self.on_drop = on_drop
        self.dropped = 0

    def __call__(self, msg: Detections) -> None:
        problem = detections_problem(msg)
        if problem is not None:
            self.dropped += 1
            if self.on_drop is not None:
                self.on_drop(self.dropped, problem)
            return
        self.accept(msg)
