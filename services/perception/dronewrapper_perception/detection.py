"""The detector-independent result of an object detector (YOLOX, HOG)."""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class Detection:
    """One detected object, in pixels of the source image (origin top-left, x right, y down).

    Attributes:
        box_xyxy: (left, top, right, bottom) in source-image px.
        score: confidence 0..1 (for YOLOX: objectness x class probability).
        class_id: index in the detector's class list (COCO: 0 = person).
        class_name: the class's name (``person``, ``car`` ...).
    """

    box_xyxy: tuple[float, float, float, float]
    score: float
    class_id: int
    class_name: str

    @property
    def center_xy(self) -> tuple[float, float]:
        """Centre of the box, px."""
        x1, y1, x2, y2 = self.box_xyxy
        return ((x1 + x2) / 2.0, (y1 + y2) / 2.0)

    @property
    def size_wh(self) -> tuple[float, float]:
        """Width and height of the box, px."""
        x1, y1, x2, y2 = self.box_xyxy
        return (x2 - x1, y2 - y1)
