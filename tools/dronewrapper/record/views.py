"""What Foxglove sees of one bus message: the same schemas for the recorder and the live server.

Every registered key gets a Foxglove-readable channel named ``/`` + key:

- telemetry, state, setpoints, detections, controller status: JSON with the JSON schema of the
  message type (:mod:`.schemas`), shaped like the ROS message;
- camera images: ``foxglove.RawImage`` or ``foxglove.CompressedImage`` (protobuf), JPEG-compressed
  on the way when asked (``jpeg_quality``);

and some keys add derived channels Foxglove's panels understand:

- detections: ``/{key}/annotations`` as ``foxglove.ImageAnnotations`` (boxes in image pixels,
  the followed target green, the others yellow, with class, score and track id);
- the vehicle pose, the simulator's true pose and the world objects: ``/tf`` as
  ``foxglove.FrameTransform`` from ``map`` (local ENU) to ``{ns}/base_link``,
  ``{ns}/base_link_true`` and ``sim/{name}``;
- the global position: ``/{key}/fix`` as ``foxglove.LocationFix`` for the map panel.

Pure functions: a decoded message in, encoded views out. The raw MessagePack is the recorder's
business (it keeps it beside these views).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cache
from typing import Any

import foxglove.messages as fox

from dronewrapper.msgs import codec, registry
from dronewrapper.msgs.geometry import PoseStamped
from dronewrapper.msgs.sensor import CompressedImage, Image, NavSatFix
from dronewrapper.msgs.vision import Detections
from dronewrapper.record.schemas import SCHEMA_ENCODING, json_schema_bytes, to_json

TF_TOPIC = "/tf"
MAP_FRAME = "map"

_TARGET_COLOR = fox.Color(r=0.1, g=0.9, b=0.2, a=1.0)
_OTHER_COLOR = fox.Color(r=1.0, g=0.85, b=0.0, a=1.0)
_TEXT_BACKGROUND = fox.Color(r=0.0, g=0.0, b=0.0, a=0.6)
_WHITE = fox.Color(r=1.0, g=1.0, b=1.0, a=1.0)


@dataclass(frozen=True)
class SchemaSpec:
    """A schema as stored in MCAP and advertised to Foxglove (name, encoding, definition)."""

    name: str
    encoding: str
    data: bytes


@dataclass(frozen=True)
class View:
    """One encoded message on one Foxglove channel (``message_encoding``: json or protobuf)."""

    topic: str
    message_encoding: str
    schema: SchemaSpec
    data: bytes


@cache
def foxglove_schema(message_class: type[Any]) -> SchemaSpec:
    """The protobuf schema of a ``foxglove.messages`` class."""
    schema = message_class.get_schema()
    return SchemaSpec(schema.name, schema.encoding, bytes(schema.data))


@cache
def message_schema(msg_type: type) -> SchemaSpec:
    """The JSON schema of a DroneWrapper message type."""
    return SchemaSpec(codec.schema_name(msg_type), SCHEMA_ENCODING, json_schema_bytes(msg_type))


def timestamp(stamp: float) -> fox.Timestamp:
    """A Foxglove timestamp from float seconds since the epoch (negative/non-finite -> 0)."""
    if not math.isfinite(stamp) or stamp <= 0.0:
        return fox.Timestamp(0, 0)
    sec = math.floor(stamp)
    nsec = min(999_999_999, round((stamp - sec) * 1e9))
    return fox.Timestamp(int(sec), int(nsec))


def _protobuf(topic: str, message: Any) -> View:
    schema = foxglove_schema(type(message))  # type: ignore[arg-type]  # mypy: type[Any] not Hashable
    return View(topic, "protobuf", schema, message.encode())


def jpeg_encode(msg: Image, quality: int) -> bytes:
    """A raw image as JPEG bytes (OpenCV, imported on first use)."""
    from dronewrapper.images import image_to_bgr, jpeg_decoder

    cv2 = jpeg_decoder()
    ok, buf = cv2.imencode(".jpg", image_to_bgr(msg), [cv2.IMWRITE_JPEG_QUALITY, int(quality)])
    if not ok:
        raise ValueError(f"JPEG encoding failed for a {msg.width}x{msg.height} image")
    return buf.tobytes()


def image_view(topic: str, msg: Image | CompressedImage, jpeg_quality: int | None) -> View:
    """A camera frame as ``foxglove.RawImage`` or ``foxglove.CompressedImage``.

    ``jpeg_quality`` (1..100) compresses raw images; None keeps them raw.
    """
    stamp = timestamp(msg.header.stamp)
    frame_id = msg.header.frame_id
    if isinstance(msg, CompressedImage):
        return _protobuf(
            topic,
            fox.CompressedImage(
                timestamp=stamp, frame_id=frame_id, data=bytes(msg.data), format=msg.format
            ),
        )
    if jpeg_quality is not None:
        return _protobuf(
            topic,
            fox.CompressedImage(
                timestamp=stamp,
                frame_id=frame_id,
                data=jpeg_encode(msg, jpeg_quality),
                format="jpeg",
            ),
        )
    return _protobuf(
        topic,
        fox.RawImage(
            timestamp=stamp,
            frame_id=frame_id,
            width=msg.width,
            height=msg.height,
            encoding=msg.encoding,
            step=msg.step,
            data=bytes(msg.data),
        ),
    )


def detection_annotations(msg: Detections) -> fox.ImageAnnotations:
    """Detections as image annotations: a box and a label per detection (pixels)."""
    stamp = timestamp(msg.header.stamp)
    boxes, labels = [], []
    for det in msg.detections:
        cx, cy = det.bbox.center.position.x, det.bbox.center.position.y
        hx, hy = det.bbox.size_x / 2.0, det.bbox.size_y / 2.0
        is_target = bool(det.id) and det.id == msg.target_id
        color = _TARGET_COLOR if is_target else _OTHER_COLOR
        corners = [(cx - hx, cy - hy), (cx + hx, cy - hy), (cx + hx, cy + hy), (cx - hx, cy + hy)]
        boxes.append(
            fox.PointsAnnotation(
                timestamp=stamp,
                type=fox.PointsAnnotationType.LineLoop,
                points=[fox.Point2(x=x, y=y) for x, y in corners],
                outline_color=color,
                thickness=3.0 if is_target else 2.0,
            )
        )
        hypothesis = det.results[0].hypothesis if det.results else None
        text = f"{hypothesis.class_id} {hypothesis.score:.2f}" if hypothesis else "?"
        if det.id:
            text += f" #{det.id}"
        if is_target:
            text += " target"
        labels.append(
            fox.TextAnnotation(
                timestamp=stamp,
                position=fox.Point2(x=cx - hx, y=max(0.0, cy - hy - 4.0)),
                text=text,
                font_size=14.0,
                text_color=_WHITE,
                background_color=_TEXT_BACKGROUND,
            )
        )
    return fox.ImageAnnotations(timestamp=stamp, points=boxes, texts=labels)


def frame_transform(msg: PoseStamped, child_frame_id: str) -> fox.FrameTransform:
    """A pose in local ENU as the transform ``map`` -> ``child_frame_id``."""
    p, q = msg.pose.position, msg.pose.orientation
    return fox.FrameTransform(
        timestamp=timestamp(msg.header.stamp),
        parent_frame_id=MAP_FRAME,
        child_frame_id=child_frame_id,
        translation=fox.Vector3(x=p.x, y=p.y, z=p.z),
        rotation=fox.Quaternion(x=q.x, y=q.y, z=q.z, w=q.w),
    )


def location_fix(msg: NavSatFix) -> fox.LocationFix:
    """The WGS-84 fix for Foxglove's map panel."""
    cov_type = {
        1: fox.LocationFixPositionCovarianceType.Approximated,
        2: fox.LocationFixPositionCovarianceType.DiagonalKnown,
        3: fox.LocationFixPositionCovarianceType.Known,
    }.get(msg.position_covariance_type, fox.LocationFixPositionCovarianceType.Unknown)
    covariance = list(msg.position_covariance) if len(msg.position_covariance) == 9 else None
    return fox.LocationFix(
        timestamp=timestamp(msg.header.stamp),
        frame_id=msg.header.frame_id,
        latitude=msg.latitude,
        longitude=msg.longitude,
        altitude=msg.altitude,
        position_covariance=covariance,
        position_covariance_type=cov_type,
    )


def _child_frame(topic: registry.Topic[Any], key: str) -> str | None:
    parts = topic.match(key) or {}
    if topic is registry.LOCAL_POSE:
        return f"{parts['ns']}/base_link"
    if topic is registry.SIM_GROUND_TRUTH:
        return f"{parts['ns']}/base_link_true"
    if topic is registry.SIM_OBJECT_POSE:
        return f"sim/{parts['name']}"
    return None


def views(
    key: str, topic: registry.Topic[Any], msg: Any, *, jpeg_quality: int | None = None
) -> list[View]:
    """Everything Foxglove shows of ``msg`` received on ``key`` (an instance of ``topic``).

    The first view is always the key's own channel (``/`` + key); derived views follow.
    """
    own = "/" + key
    if isinstance(msg, Image | CompressedImage):
        return [image_view(own, msg, jpeg_quality)]
    schema = message_schema(topic.type)  # type: ignore[arg-type]  # mypy: type[Any] not Hashable
    out = [View(own, "json", schema, to_json(msg))]
    if isinstance(msg, Detections):
        out.append(_protobuf(own + "/annotations", detection_annotations(msg)))
    elif isinstance(msg, PoseStamped):
        child = _child_frame(topic, key)
        if child is not None:
            out.append(_protobuf(TF_TOPIC, frame_transform(msg, child)))
    elif isinstance(msg, NavSatFix):
        out.append(_protobuf(own + "/fix", location_fix(msg)))
    return out
