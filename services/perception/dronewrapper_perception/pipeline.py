"""One frame's work: detect, describe appearance, track, and build the Detections message.

:class:`Pipeline` is shared by the service node and the ``dronewrapper detect`` command. Time
is passed in (the frame stamp, seconds), so the pipeline is deterministic given its frames.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import cv2
import numpy as np

from dronewrapper.msgs import (
    BoundingBox2D,
    Detection2D,
    Detections,
    Header,
    ObjectHypothesis,
    ObjectHypothesisWithPose,
)
from dronewrapper_perception.appearance import appearance_histogram
from dronewrapper_perception.config import Config
from dronewrapper_perception.detection import Detection
from dronewrapper_perception.detectors import BlobDetection, Detector, build_detector
from dronewrapper_perception.tracking import Tracker, TrackingResult, make_tracker


@dataclass(frozen=True)
class FrameResult:
    """Detections of one frame (best first), their track ids and the target.

    ``processing_time`` is in seconds (detect + track, plus decode when the caller adds it).
    """

    detections: list[Detection]
    tracking: TrackingResult
    image_wh: tuple[int, int]
    processing_time: float

    def target(self) -> Detection | None:
        index = self.tracking.target_index
        return None if index is None else self.detections[index]


def make_tracker_for(config: Config) -> Tracker:
    if config.tracker == "kalman":
        return make_tracker("kalman", max_coast_s=config.max_coast_s)
    if config.tracker == "paper":
        return make_tracker(
            "paper", fifo_length=config.paper_fifo_length, gate_px=config.paper_gate_px
        )
    return make_tracker("none")


class Pipeline:
    """Detector + tracker for a stream of frames."""

    def __init__(
        self, config: Config, detector: Detector | None = None, tracker: Tracker | None = None
    ) -> None:
        self.config = config
        self.detector = detector or build_detector(config)
        self.tracker = tracker or make_tracker_for(config)

    @property
    def detector_name(self) -> str:
        return self.detector.name

    def warm_up(self, width: int = 640, height: int = 480) -> None:
        """Run the detector once so the first real frame is not slow (allocations, JIT)."""
        self.detector.detect(np.zeros((height, width, 3), np.uint8))

    def process(self, bgr: np.ndarray, t: float) -> FrameResult:
        """Detect and track in one BGR frame taken at time ``t`` (s)."""
        start = time.perf_counter()
        detections = self.detector.detect(bgr)[: self.config.max_detections]
        features = None
        if self.tracker.needs_appearance:
            features = [appearance_histogram(bgr, d.box_xyxy) for d in detections]
        image_wh = (bgr.shape[1], bgr.shape[0])
        tracking = self.tracker.update(detections, t, features, image_wh)
        return FrameResult(
            detections,
            tracking,
            image_wh,
            time.perf_counter() - start,
        )


def to_message(
    result: FrameResult,
    *,
    stamp: float,
    frame_id: str,
    detector: str,
    seq: int = 0,
    extra_time: float = 0.0,
) -> Detections:
    """The Detections message (vision_msgs/Detection2DArray shape) of one processed frame.

    ``header.stamp`` is the source frame's stamp; colour blobs carry their centroid as the box
    centre and the enclosing circle's radius; ``extra_time`` (s) is added to the processing
    time (e.g. the decode).
    """
    header = Header(stamp=stamp, frame_id=frame_id, seq=seq)
    out = []
    for det, track_id in zip(result.detections, result.tracking.track_ids, strict=True):
        width, height = det.size_wh
        cx, cy = det.center_xy
        out.append(
            Detection2D(
                header=header,
                results=[
                    ObjectHypothesisWithPose(
                        hypothesis=ObjectHypothesis(class_id=det.class_name, score=det.score)
                    )
                ],
                bbox=BoundingBox2D.at(cx, cy, width, height),
                id=track_id,
                circle_radius=det.circle_radius if isinstance(det, BlobDetection) else 0.0,
            )
        )
    return Detections(
        header=header,
        detections=out,
        image_width=result.image_wh[0],
        image_height=result.image_wh[1],
        detector=detector,
        target_id=result.tracking.target_id,
        processing_time=result.processing_time + extra_time,
    )


def annotate(bgr: np.ndarray, result: FrameResult) -> np.ndarray:
    """A copy of the frame with boxes, ids and scores drawn; the target in red, thicker."""
    image = bgr.copy()
    target = result.tracking.target_index
    for i, (det, track_id) in enumerate(
        zip(result.detections, result.tracking.track_ids, strict=True)
    ):
        x1, y1, x2, y2 = (round(v) for v in det.box_xyxy)
        colour, thickness = ((0, 0, 255), 3) if i == target else ((0, 200, 0), 1)
        cv2.rectangle(image, (x1, y1), (x2, y2), colour, thickness)
        if isinstance(det, BlobDetection):
            cx, cy = (round(v) for v in det.centroid_xy)
            cv2.circle(image, (cx, cy), round(det.circle_radius), colour, 1)
            cv2.drawMarker(image, (cx, cy), colour, cv2.MARKER_CROSS, 10)
        label = f"{track_id} {det.class_name} {det.score:.2f}".strip()
        cv2.putText(image, label, (x1, max(12, y1 - 4)), cv2.FONT_HERSHEY_SIMPLEX, 0.45, colour, 1)
    return image


def encode_jpeg(bgr: np.ndarray, quality: int = 80) -> bytes:
    """JPEG bytes of a BGR image."""
    ok, buffer = cv2.imencode(".jpg", bgr, [cv2.IMWRITE_JPEG_QUALITY, int(quality)])
    if not ok:
        raise ValueError("JPEG encoding failed")
    return buffer.tobytes()
