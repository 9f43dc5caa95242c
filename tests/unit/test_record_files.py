"""Recorder and reader without a network: schemas, Foxglove views, MCAP content, cut files."""

from __future__ import annotations

import io
import json
import math

import numpy as np
import pytest
from mcap.reader import make_reader

from dronewrapper.msgs import (
    BoundingBox2D,
    CompressedImage,
    ControllerStatus,
    Detection2D,
    Detections,
    Header,
    Image,
    NavSatFix,
    ObjectHypothesis,
    ObjectHypothesisWithPose,
    Point,
    Pose,
    PoseStamped,
    codec,
    registry,
)
from dronewrapper.record.reader import image_from_view, read_bus, summarize
from dronewrapper.record.recorder import Recorder
from dronewrapper.record.schemas import json_schema
from dronewrapper.record.views import timestamp, views

T0 = 1_700_000_000.25


def _image(i: int, w: int = 32, h: int = 24) -> Image:
    pixels = np.zeros((h, w, 3), np.uint8)
    pixels[:, : w // 2] = (0, 0, 200)  # a red left half (BGR)
    pixels[0, 0] = (i, i, i)
    return Image(
        header=Header(stamp=T0 + i / 30, frame_id="cam_frontal"),
        height=h,
        width=w,
        step=w * 3,
        data=pixels.tobytes(),
    )


def _detections(stamp: float) -> Detections:
    det = Detection2D(
        results=[ObjectHypothesisWithPose(hypothesis=ObjectHypothesis(class_id="red", score=0.9))],
        bbox=BoundingBox2D.at(100, 80, 40, 20),
        id="3",
    )
    return Detections(header=Header(stamp=stamp), detections=[det], target_id="3")


@pytest.mark.parametrize("topic", registry.TOPICS.values(), ids=lambda t: t.template)
def test_every_registered_type_has_a_self_contained_ros_shaped_schema(topic):
    schema = json_schema(topic.type)
    text = json.dumps(schema)
    assert "$ref" not in text and "$defs" not in text
    assert schema["type"] == "object"
    assert set(schema["properties"]) == set(topic.type.__struct_fields__)
    if "header" in schema["properties"]:
        assert schema["properties"]["header"]["properties"]["stamp"]["type"] == "number"


def test_pose_schema_is_shaped_like_geometry_msgs():
    pose = json_schema(PoseStamped)["properties"]["pose"]["properties"]
    assert set(pose["position"]["properties"]) == {"x", "y", "z"}
    assert set(pose["orientation"]["properties"]) == {"x", "y", "z", "w"}


def test_timestamps_split_into_seconds_and_nanoseconds():
    ts = timestamp(12.5)
    assert (ts.sec, ts.nsec) == (12, 500_000_000)
    assert (timestamp(math.nan).sec, timestamp(-1.0).sec) == (0, 0)


def test_views_of_each_kind_of_message():
    pose = PoseStamped(header=Header(stamp=T0), pose=Pose(position=Point(x=1, y=2, z=3)))
    key = registry.LOCAL_POSE.key("drone")
    got = views(key, registry.LOCAL_POSE, pose)
    assert [(v.topic, v.schema.name) for v in got] == [
        ("/" + key, "dronewrapper/v1/PoseStamped"),
        ("/tf", "foxglove.FrameTransform"),
    ]
    assert json.loads(got[0].data)["pose"]["position"] == {"x": 1.0, "y": 2.0, "z": 3.0}

    key = registry.DETECTIONS.key("drone")
    got = views(key, registry.DETECTIONS, _detections(T0))
    assert [v.schema.name for v in got] == [
        "dronewrapper/v1/Detections",
        "foxglove.ImageAnnotations",
    ]

    key = registry.GLOBAL_POSITION.key("drone")
    got = views(key, registry.GLOBAL_POSITION, NavSatFix(latitude=47.4, longitude=8.5))
    assert got[1].topic == "/" + key + "/fix" and got[1].schema.name == "foxglove.LocationFix"

    key = registry.IMAGE_RAW.key("drone", camera="cam_frontal")
    (raw,) = views(key, registry.IMAGE_RAW, _image(1))
    (jpeg,) = views(key, registry.IMAGE_RAW, _image(1), jpeg_quality=80)
    assert raw.schema.name == "foxglove.RawImage" and jpeg.schema.name == "foxglove.CompressedImage"
    assert len(jpeg.data) < len(raw.data)


def test_image_views_rebuild_the_bus_image():
    key = registry.IMAGE_RAW.key("drone", camera="cam_frontal")
    img = _image(7)
    (raw,) = views(key, registry.IMAGE_RAW, img)
    schema = type("S", (), {"name": raw.schema.name, "data": raw.schema.data})
    back = image_from_view(schema, raw.data, "view")
    assert bytes(back.data) == bytes(img.data) and back.header.stamp == pytest.approx(T0 + 7 / 30)
    (jpeg,) = views(key, registry.IMAGE_RAW, img, jpeg_quality=90)
    schema = type("S", (), {"name": jpeg.schema.name, "data": jpeg.schema.data})
    lossy = image_from_view(schema, jpeg.data, "jpeg")
    pixels = np.frombuffer(lossy.data, np.uint8).reshape(24, 32, 3)
    assert isinstance(lossy, Image) and abs(int(pixels[12, 4, 2]) - 200) < 20


def _record(f: io.BufferedIOBase | io.BytesIO, n: int, **kw) -> Recorder:
    rec = Recorder(f, **kw)
    for i in range(n):
        t = T0 + i / 30
        ns = int(t * 1e9)
        camera = registry.IMAGE_RAW.key("drone", camera="cam_frontal")
        rec.write(camera, codec.encode(_image(i)), ns)
        pose = PoseStamped(header=Header(stamp=t), pose=Pose(position=Point(x=i)))
        rec.write(registry.LOCAL_POSE.key("drone"), codec.encode(pose), ns)
        status = ControllerStatus(header=Header(stamp=t), error_x=0.1 * i)
        rec.write(registry.CONTROLLER_STATUS.key("drone"), codec.encode(status), ns)
        rec.write(registry.DETECTIONS.key("drone"), codec.encode(_detections(t)), ns)
    return rec


def test_recording_reads_back_with_the_mcap_reader(tmp_path):
    path = tmp_path / "flight.mcap"
    with path.open("wb") as f:
        _record(f, 10, jpeg_quality=None).close()
    with path.open("rb") as f:
        reader = make_reader(f)
        summary = reader.get_summary()
        topics = {c.topic: c for c in summary.channels.values()}
        counts = summary.statistics.channel_message_counts
        assert summary.chunk_indexes  # chunked
        assert {summary.schemas[c.schema_id].name for c in topics.values() if c.schema_id} >= {
            "foxglove.RawImage",
            "foxglove.FrameTransform",
            "foxglove.ImageAnnotations",
            "dronewrapper/v1/ControllerStatus",
        }
        assert counts[topics["drone/mavros/local_position/pose"].id] == 10
        assert counts[topics["/drone/controller/status"].id] == 10
        assert "drone/cam_frontal/image_raw" not in topics  # pixels stored once, in the view
        decoded = [
            json.loads(m.data)
            for _, c, m in reader.iter_messages(topics=["/drone/controller/status"])
        ]
        assert [d["error_x"] for d in decoded] == pytest.approx([0.1 * i for i in range(10)])
        assert decoded[0]["detection_age"] is None  # inf: no JSON number


def test_bus_messages_come_back_byte_exact_and_in_order(tmp_path):
    path = tmp_path / "flight.mcap"
    with path.open("wb") as f:
        _record(f, 5).close()
    got = list(read_bus(path))
    assert len(got) == 20
    assert [m.log_time_ns for m in got] == sorted(m.log_time_ns for m in got)
    images = [m for m in got if m.key == "drone/cam_frontal/image_raw"]
    assert [codec.encode(_image(i)) for i in range(5)] == [m.payload for m in images]
    assert list(read_bus(path, ["drone/mavros/**"]))[3].decode().pose.position.x == 3


def test_cut_file_reads_to_its_last_complete_chunk(tmp_path):
    now = [0.0]
    path = tmp_path / "cut.mcap"
    f = path.open("wb")
    rec = Recorder(f, flush_period_s=1.0, clock=lambda: now[0], jpeg_quality=70)
    for i in range(30):
        now[0] = i / 10
        t = T0 + i / 10
        pose = PoseStamped(header=Header(stamp=t), pose=Pose(position=Point(x=i)))
        rec.write(registry.LOCAL_POSE.key("drone"), codec.encode(pose), int(t * 1e9))
    f.flush()  # what a SIGKILL leaves: flushed chunks, no summary, no footer
    data = path.read_bytes()
    f.close()
    for cut in (len(data), len(data) - 7):
        path.write_bytes(data[:cut])
        info = summarize(path)
        assert info.truncated
        poses = list(read_bus(path))
        # flushed every second of the injected clock: 2 full seconds at 10 Hz at least
        assert 20 <= len(poses) <= 30
        assert [m.decode().pose.position.x for m in poses] == list(range(len(poses)))


def test_unknown_keys_and_bad_payloads_keep_their_raw_bytes(tmp_path):
    path = tmp_path / "odd.mcap"
    with path.open("wb") as f, Recorder(f) as rec:
        rec.write("other/thing", b"\x01\x02", 1)
        rec.write(registry.LOCAL_POSE.key("drone"), b"\xc1garbage", 2)
        assert rec.decode_errors[registry.LOCAL_POSE.key("drone")] == 1
    assert [(m.key, m.payload) for m in read_bus(path)] == [
        ("other/thing", b"\x01\x02"),
        ("drone/mavros/local_position/pose", b"\xc1garbage"),
    ]


def test_a_malformed_image_is_kept_raw_and_recording_goes_on(tmp_path):
    key = registry.IMAGE_RAW.key("drone", camera="cam_frontal")
    short = Image(header=Header(stamp=T0), height=24, width=32, step=96, data=b"\x00" * 10)
    path = tmp_path / "bad.mcap"
    with path.open("wb") as f, Recorder(f, jpeg_quality=80) as rec:
        rec.write(key, codec.encode(short), 1)
        rec.write(key, codec.encode(_image(2)), 2)
        assert rec.view_errors[key] == 1
    got = list(read_bus(path))
    assert [m.payload == codec.encode(short) for m in got] == [True, False]
    assert got[1].decode().width == 32


def test_recorder_rejects_bad_settings():
    with pytest.raises(ValueError, match="jpeg_quality"):
        Recorder(io.BytesIO(), jpeg_quality=0)
    with pytest.raises(ValueError, match="compression"):
        Recorder(io.BytesIO(), compression="bz2")


def test_info_text_names_channels_counts_and_rates(tmp_path):
    path = tmp_path / "flight.mcap"
    with path.open("wb") as f:
        _record(f, 31).close()
    info = summarize(path)
    assert not info.truncated and info.duration_s == pytest.approx(1.0, abs=1e-6)
    pose = next(c for c in info.channels if c.topic == "drone/mavros/local_position/pose")
    assert pose.count == 31 and pose.rate_hz == pytest.approx(30.0)
    assert "/drone/perception/detections/annotations" in info.text()


def test_compressed_bus_images_pass_through(tmp_path):
    key = registry.IMAGE_COMPRESSED.key("drone", camera="cam_frontal")
    msg = CompressedImage(header=Header(stamp=T0), format="jpeg", data=b"\xff\xd8not-really")
    path = tmp_path / "c.mcap"
    with path.open("wb") as f, Recorder(f) as rec:
        rec.write(key, codec.encode(msg), 5)
    (back,) = read_bus(path)
    assert back.payload == codec.encode(msg)


def test_the_layout_in_the_repository_is_the_generated_one_and_names_real_topics(tmp_path):
    from dronewrapper.record.layout import layout_json
    from support import REPO

    stored = (REPO / "docs" / "foxglove_layout.json").read_text()
    assert stored == layout_json(), "regenerate: python -m dronewrapper.record.layout"
    path = tmp_path / "flight.mcap"
    with path.open("wb") as f:
        rec = _record(f, 2)
        fix = NavSatFix(header=Header(stamp=T0), latitude=47.4)
        rec.write(registry.GLOBAL_POSITION.key("drone"), codec.encode(fix), 1)
        rec.close()
    topics = {c.topic for c in summarize(path).channels}
    text = json.dumps(json.loads(stored))
    for topic in (
        "/drone/cam_frontal/image_raw",
        "/drone/perception/detections/annotations",
        "/drone/controller/status",
        "/drone/mavros/global_position/global/fix",
    ):
        assert topic in topics and f'"{topic}' in text, topic
