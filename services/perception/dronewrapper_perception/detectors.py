"""The detectors behind one interface: ``name`` and ``detect(bgr) -> list[Detection]``.

Colour blobs come back as :class:`BlobDetection` (a Detection with the blob's centroid and
enclosing-circle radius), so the tracker and the message builder treat every detector alike.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Protocol

import numpy as np

from dronewrapper_perception.color_filter import ColorRange, detect_color
from dronewrapper_perception.config import Config
from dronewrapper_perception.detection import Detection


class Detector(Protocol):
    name: str

    def detect(self, bgr: np.ndarray) -> list[Detection]: ...


@dataclass(frozen=True)
class BlobDetection(Detection):
    """A colour blob: the box is its bounding box; ``centroid_xy`` its centre of mass (px);
    ``circle_radius`` the radius of its minimum enclosing circle (px)."""

    centroid_xy: tuple[float, float] = (0.0, 0.0)
    circle_radius: float = 0.0

    @property
    def center_xy(self) -> tuple[float, float]:
        """The centroid (the paper steers on it), not the box centre."""
        return self.centroid_xy


class ColorDetector:
    """The paper's colour pipeline as a detector; blobs largest first, score 1."""

    name = "color"

    def __init__(
        self,
        ranges: Sequence[ColorRange],
        *,
        label: str = "red",
        blur: int = 11,
        min_area_px: float = 20.0,
        scale: float = 1.0,
    ) -> None:
        self.ranges = tuple(ranges)
        self.label = label
        self.blur = blur
        self.min_area_px = min_area_px
        self.scale = scale

    def detect(self, bgr: np.ndarray) -> list[Detection]:
        return [
            BlobDetection(
                box_xyxy=blob.bbox_xyxy,
                score=1.0,
                class_id=0,
                class_name=self.label,
                centroid_xy=blob.centroid_xy,
                circle_radius=blob.radius_px,
            )
            for blob in detect_color(
                bgr, self.ranges, blur=self.blur, min_area_px=self.min_area_px, scale=self.scale
            )
        ]


def build_detector(config: Config) -> Detector:
    """The detector the config asks for.

    Raises:
        ModelFileError: YOLOX without a usable model file (missing, wrong checksum).
    """
    kind = config.detector_kind()
    if kind == "color":
        return ColorDetector(
            config.color_ranges_resolved(),
            label=config.color_label(),
            blur=config.blur_px,
            min_area_px=config.min_area_px,
            scale=config.color_scale,
        )
    if kind == "yolox":
        from dronewrapper_perception.yolox import YoloxDetector

        return YoloxDetector(
            config.model_path,
            input_size=config.input_size,
            score_threshold=config.score_threshold,
            nms_threshold=config.nms_threshold,
            classes=tuple(config.classes),
            providers=config.provider_list() or None,
            threads=config.threads,
            checksum=config.checksum,
            spinning=config.thread_spinning,
            strict_providers=config.providers_strict,
        )
    from dronewrapper_perception.hog import HogDetector

    return HogDetector(score_threshold=config.score_threshold, nms_threshold=config.nms_threshold)
