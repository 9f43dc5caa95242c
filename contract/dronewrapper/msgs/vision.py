"""Detections shaped like ROS vision_msgs/Detection2DArray, with tracking extensions.

Pixel coordinates: origin at the top-left of the image, x to the right, y down, in pixels of
the source image (``Detections.image_width`` x ``image_height``).
"""

from __future__ import annotations

import msgspec

from dronewrapper.msgs.std import Header


class Point2D(msgspec.Struct, kw_only=True, frozen=True):
    """A point in image pixels."""

    x: float = 0.0
    y: float = 0.0


class Pose2D(msgspec.Struct, kw_only=True, frozen=True):
    """vision_msgs/Pose2D: position (px) and rotation (rad, 0 for axis-aligned boxes)."""

    position: Point2D = msgspec.field(default_factory=Point2D)
    theta: float = 0.0


class BoundingBox2D(msgspec.Struct, kw_only=True, frozen=True):
    """vision_msgs/BoundingBox2D: centre and full size in pixels."""

    center: Pose2D = msgspec.field(default_factory=Pose2D)
    size_x: float = 0.0
    size_y: float = 0.0

    @classmethod
    def at(cls, cx: float, cy: float, width: float, height: float) -> BoundingBox2D:
        """The axis-aligned box of ``width`` x ``height`` px centred at (``cx``, ``cy``) px."""
        return cls(center=Pose2D(position=Point2D(x=cx, y=cy)), size_x=width, size_y=height)


class ObjectHypothesis(msgspec.Struct, kw_only=True, frozen=True):
    """vision_msgs/ObjectHypothesis: class name (``person``, ``red`` ...) and score 0..1."""

    class_id: str = ""
    score: float = 0.0


class ObjectHypothesisWithPose(msgspec.Struct, kw_only=True, frozen=True):
    """vision_msgs/ObjectHypothesisWithPose (the 3-D pose is not estimated, so it is omitted)."""

    hypothesis: ObjectHypothesis = msgspec.field(default_factory=ObjectHypothesis)


class Detection2D(msgspec.Struct, kw_only=True, frozen=True):
    """vision_msgs/Detection2D plus ``circle_radius``.

    Attributes:
        id: the track id ("" when the detector does not track); stable across frames for one
            object when a tracker runs.
        circle_radius: radius in px of the minimum enclosing circle (colour blobs; 0 if unused).
    """

    header: Header = msgspec.field(default_factory=Header)
    results: list[ObjectHypothesisWithPose] = msgspec.field(default_factory=list)
    bbox: BoundingBox2D = msgspec.field(default_factory=BoundingBox2D)
    id: str = ""
    circle_radius: float = 0.0


class Detections(msgspec.Struct, kw_only=True, frozen=True):
    """vision_msgs/Detection2DArray for one processed frame, plus what a follower needs.

    Attributes:
        header: ``stamp`` is the source camera frame's capture stamp; ``frame_id`` the camera.
        detections: every detection kept after filtering, best first.
        image_width, image_height: size of the source image in px.
        detector: ``color``, ``yolox`` or ``hog``.
        target_id: ``id`` of the detection chosen as the followed target, "" when none.
        processing_time: seconds spent on this frame (decode + detect + track).
        receive_time: when the frame reached perception (s, Unix time like ``header.stamp``);
            0 from publishers that do not measure it.
        queue_time: seconds the frame waited in perception (arrival -> processing starts);
            0 from publishers that do not measure it.
        decode_time: seconds of ``processing_time`` spent decoding the frame to pixels; 0 from
            publishers that do not measure it.
    """

    header: Header = msgspec.field(default_factory=Header)
    detections: list[Detection2D] = msgspec.field(default_factory=list)
    image_width: int = 0
    image_height: int = 0
    detector: str = ""
    target_id: str = ""
    processing_time: float = 0.0
    receive_time: float = 0.0
    queue_time: float = 0.0
    decode_time: float = 0.0

    def target(self) -> Detection2D | None:
        """The followed detection, or None."""
        if not self.target_id:
            return None
        for det in self.detections:
            if det.id == self.target_id:
                return det
        return None
