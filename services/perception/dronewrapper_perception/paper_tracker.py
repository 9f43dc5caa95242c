"""The DroneWrapper paper's follow-person identification, with the seed code's bugs fixed.

A FIFO of the target's last 5 centroids (the code had 3), the detection nearest to their mean in
x *and* y (the code's typo dropped y), the first pick by the highest *numeric* score (the code
compared strings), the identity checked even when only one detection is present (the code took
any single detection), and no (0, 0) pushed into the FIFO on a miss (the code dragged the mean
to the image corner).
"""

from __future__ import annotations

import itertools
from collections import deque

import numpy as np

from dronewrapper_perception.detection import Detection
from dronewrapper_perception.track_result import TrackingResult


def _centre(det: Detection) -> np.ndarray:
    return np.array(det.center_xy, dtype=np.float64)


class PaperTracker:
    """The paper's follow-person identification, with the seed code's bugs fixed.

    Args:
        fifo_length: centroids remembered (the paper's 5).
        gate_px: a detection farther than this from the FIFO mean is not the target (px);
            this also applies when only one detection is present.
        lost_after_s: after this long without the target, forget it and pick again by score.
    """

    needs_appearance = False

    def __init__(
        self, fifo_length: int = 5, gate_px: float = 120.0, lost_after_s: float = 1.0
    ) -> None:
        if fifo_length < 1:
            raise ValueError("fifo_length must be >= 1")
        self.fifo: deque[tuple[float, float]] = deque(maxlen=fifo_length)
        self.gate_px = gate_px
        self.lost_after_s = lost_after_s
        self._last_seen = -np.inf
        self._picks = itertools.count(1)
        self._target_id = ""

    def reset(self) -> None:
        """Forget the target."""
        self.fifo.clear()
        self._target_id = ""

    def fifo_mean(self) -> tuple[float, float] | None:
        """Mean of the remembered centroids (px), None before the first pick."""
        if not self.fifo:
            return None
        xs, ys = zip(*self.fifo, strict=True)
        return (float(np.mean(xs)), float(np.mean(ys)))

    def update(self, detections, t, features=None, image_wh=None) -> TrackingResult:
        if self.fifo and t - self._last_seen > self.lost_after_s:
            self.reset()
        chosen: int | None = None
        if detections:
            mean = self.fifo_mean()
            if mean is None:
                chosen = max(range(len(detections)), key=lambda i: float(detections[i].score))
                self._target_id = f"p{next(self._picks)}"
            else:
                dists = [float(np.hypot(*(_centre(d) - mean))) for d in detections]
                nearest = int(np.argmin(dists))
                if dists[nearest] <= self.gate_px:
                    chosen = nearest
        ids = ["" for _ in detections]
        if chosen is None:
            return TrackingResult(tuple(ids))
        self.fifo.append(detections[chosen].center_xy)
        self._last_seen = t
        ids[chosen] = self._target_id
        return TrackingResult(tuple(ids), self._target_id, chosen)
