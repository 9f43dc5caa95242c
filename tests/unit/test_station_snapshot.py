"""Telemetry as the page shows it: ages, staleness, boxes as image fractions."""

from __future__ import annotations

import math
import time

from dronewrapper.msgs.geometry import Point, Pose, PoseStamped, Quaternion
from dronewrapper.msgs.mavros import StatusText
from dronewrapper.msgs.std import Header
from dronewrapper.msgs.vision import (
    BoundingBox2D,
    Detection2D,
    Detections,
    ObjectHypothesis,
    ObjectHypothesisWithPose,
)
from dronewrapper_ground_station import snapshot


def test_stale_limit_scales_with_the_rate_and_is_at_least_a_second() -> None:
    assert snapshot.stale_limit(30.0, 3.0) == 1.0
    assert snapshot.stale_limit(1.0, 3.0) == 3.0
    assert snapshot.stale_limit(0.0, 3.0) == 3.0


def test_section_marks_stale_values() -> None:
    assert snapshot.section(None, 0.1, 1.0) is None
    assert snapshot.section({"z": 1.0}, 0.25, 1.0) == {"z": 1.0, "age": 0.25, "stale": False}
    assert snapshot.section({"z": 1.0}, 1.5, 1.0)["stale"] is True


def test_pose_fields_in_enu_with_yaw() -> None:
    half = math.pi / 4  # yaw 90 degrees: facing north
    msg = PoseStamped(
        header=Header(stamp=5.0),
        pose=Pose(
            position=Point(x=1.0, y=2.0, z=3.0),
            orientation=Quaternion(x=0.0, y=0.0, z=math.sin(half), w=math.cos(half)),
        ),
    )
    fields = snapshot.pose_fields(msg)
    assert (fields["x"], fields["y"], fields["z"], fields["stamp"]) == (1.0, 2.0, 3.0, 5.0)
    assert math.isclose(fields["yaw"], math.pi / 2)


def test_detections_become_fractions_of_the_image_with_the_target() -> None:
    def det(ident: str, cx: float, cy: float) -> Detection2D:
        return Detection2D(
            id=ident,
            bbox=BoundingBox2D.at(cx, cy, 64, 48),
            results=[
                ObjectHypothesisWithPose(hypothesis=ObjectHypothesis(class_id="person", score=0.9))
            ],
        )

    msg = Detections(
        header=Header(stamp=7.0, frame_id="cam_frontal"),
        detections=[det("1", 320, 240), det("2", 32, 24)],
        image_width=640,
        image_height=480,
        target_id="2",
    )
    fields = snapshot.detection_fields(msg)
    first, second = fields["boxes"]
    assert (first["x"], first["y"], first["w"], first["h"]) == (0.45, 0.45, 0.1, 0.1)
    assert (second["x"], second["y"]) == (0.0, 0.0)
    assert not first["target"] and second["target"]
    assert fields["camera"] == "cam_frontal" and second["label"] == "person"


def test_status_text_severity_names() -> None:
    entry = snapshot.status_text_entry(StatusText(header=Header(stamp=1.0), severity=3, text="x"))
    shown = time.strftime("%H:%M:%S", time.localtime(1.0))  # the event's own time, local
    assert entry == {"stamp": 1.0, "time": shown, "severity": "error", "text": "x"}
    assert snapshot.status_text_entry(StatusText(severity=42))["severity"] == "info"
