"""What a tracker gives for one frame, and what the perception pipeline needs of a tracker.

A tracker is pure: ``update(detections, t, features, image_wh)`` takes one frame's detections
(source px), its time ``t`` in seconds (the frame stamp), optional appearance descriptors (one
per detection, see :mod:`appearance`) and the frame's (width, height) in px, and returns a
:class:`TrackingResult`: a track id per detection (same order) and the followed target's id.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Protocol

import numpy as np

from dronewrapper_perception.detection import Detection


@dataclass(frozen=True)
class TrackingResult:
    """Track ids for one frame's detections (same order as given) and the followed target.

    Attributes:
        track_ids: one id per input detection ("" = not tracked).
        target_id: id of the target when it is visible in this frame, else "".
        target_index: index of the target among the input detections, or None.
    """

    track_ids: tuple[str, ...]
    target_id: str = ""
    target_index: int | None = None


class Tracker(Protocol):
    """What the node needs from a tracker."""

    needs_appearance: bool

    def update(
        self,
        detections: Sequence[Detection],
        t: float,
        features: Sequence[np.ndarray | None] | None = None,
        image_wh: tuple[int, int] | None = None,
    ) -> TrackingResult: ...

    def reset(self) -> None: ...
