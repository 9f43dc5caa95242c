"""OpenCV's built-in HOG + linear SVM people detector: the zero-download fallback.

No model file is needed (the SVM coefficients ship inside OpenCV). It is slower and weaker than
YOLOX (upright, roughly 64x128 px and larger people only); use it when no ONNX model is
configured. Returns the same :class:`Detection` as YOLOX, class 0 ``person``.
"""

from __future__ import annotations

import cv2
import numpy as np

from dronewrapper_perception.detection import Detection
from dronewrapper_perception.yolox import nms


class HogDetector:
    """People detection with ``cv2.HOGDescriptor.getDefaultPeopleDetector``.

    Args:
        score_threshold: minimum SVM margin mapped to 0..1 as ``1 - exp(-margin)``.
        nms_threshold: IoU above which a weaker overlapping box is dropped.
        max_width: frames wider than this (px) are downscaled first (speed); boxes come back in
            source px.
        scale: pyramid step of ``detectMultiScale``.
    """

    name = "hog"

    def __init__(
        self,
        *,
        score_threshold: float = 0.3,
        nms_threshold: float = 0.45,
        max_width: int = 640,
        scale: float = 1.1,
    ) -> None:
        self.hog = cv2.HOGDescriptor()
        self.hog.setSVMDetector(np.asarray(cv2.HOGDescriptor.getDefaultPeopleDetector()))
        self.score_threshold = score_threshold
        self.nms_threshold = nms_threshold
        self.max_width = max_width
        self.scale = scale

    def detect(self, bgr: np.ndarray) -> list[Detection]:
        """People in a BGR uint8 image, best first, boxes in source px."""
        if bgr.ndim != 3 or bgr.shape[2] != 3 or bgr.dtype != np.uint8:
            raise ValueError(f"image must be HxWx3 uint8 BGR, got {bgr.dtype} {bgr.shape}")
        h, w = bgr.shape[:2]
        factor = min(1.0, self.max_width / w)
        image = cv2.resize(bgr, (round(w * factor), round(h * factor))) if factor < 1 else bgr
        if image.shape[0] < 128 or image.shape[1] < 64:
            return []
        rects, weights = self.hog.detectMultiScale(
            image, winStride=(8, 8), padding=(8, 8), scale=self.scale
        )
        if len(rects) == 0:
            return []
        margins = np.asarray(weights, np.float64).reshape(-1)
        scores = 1.0 - np.exp(-np.maximum(margins, 0.0))
        boxes = np.asarray(rects, np.float64).reshape(-1, 4) / factor
        boxes[:, 2:] += boxes[:, :2]
        boxes[:, [0, 2]] = np.clip(boxes[:, [0, 2]], 0, w)
        boxes[:, [1, 3]] = np.clip(boxes[:, [1, 3]], 0, h)
        keep = [
            i for i in nms(boxes, scores, self.nms_threshold) if scores[i] >= self.score_threshold
        ]
        return [
            Detection(
                box_xyxy=tuple(float(v) for v in boxes[i]),  # type: ignore[arg-type]
                score=float(scores[i]),
                class_id=0,
                class_name="person",
            )
            for i in keep
        ]
