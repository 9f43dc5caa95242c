"""Identification of the followed object across frames: choose a tracker by name.

- ``paper``: :class:`~dronewrapper_perception.paper_tracker.PaperTracker`, the DroneWrapper
  paper's method with the seed code's bugs fixed;
- ``kalman``: :class:`~dronewrapper_perception.kalman_tracker.KalmanTracker`, motion +
  appearance with re-identification, reasoning in seconds;
- ``none``: :class:`NoTracker`, the first detection is the target.

All are pure (see :mod:`~dronewrapper_perception.track_result` for the interface).
"""

from __future__ import annotations

from dronewrapper_perception.kalman_tracker import KalmanTracker, prominence
from dronewrapper_perception.paper_tracker import PaperTracker
from dronewrapper_perception.track_result import Tracker, TrackingResult

__all__ = [
    "TRACKERS",
    "KalmanTracker",
    "NoTracker",
    "PaperTracker",
    "Tracker",
    "TrackingResult",
    "make_tracker",
    "prominence",
]

TRACKERS = ("paper", "kalman", "none")


class NoTracker:
    """No identity: the target is the first detection (highest score, or the largest blob).

    The target gets the fixed id ``target``; other detections get no id.
    """

    needs_appearance = False
    target_label = "target"

    def update(self, detections, t, features=None, image_wh=None) -> TrackingResult:
        if not detections:
            return TrackingResult(())
        ids = (self.target_label,) + ("",) * (len(detections) - 1)
        return TrackingResult(ids, self.target_label, 0)

    def reset(self) -> None:
        pass


def make_tracker(name: str, **options) -> Tracker:
    """A tracker by config name: ``paper``, ``kalman`` or ``none``."""
    if name == "paper":
        return PaperTracker(**options)
    if name == "kalman":
        return KalmanTracker(**options)
    if name == "none":
        return NoTracker()
    raise ValueError(f"unknown tracker {name!r} (known: {', '.join(TRACKERS)})")
