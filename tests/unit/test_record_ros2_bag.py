"""A recording converted to a ROS 2 bag reads back with rosbags (an independent MCAP + CDR
reader with ROS 2 Jazzy's own definitions), every message equal to the one recorded, and with
Foxglove's own decoder (mcap-ros2-support, from the schemas in the file)."""

from __future__ import annotations

import math

from rosbags.highlevel import AnyReader
from rosbags.typesys import Stores, get_typestore

from dronewrapper.msgs import codec, registry
from dronewrapper.msgs.control import ControllerStatus
from dronewrapper.msgs.geometry import Point, Pose, PoseStamped, Twist, TwistStamped, Vector3
from dronewrapper.msgs.mavros import ExtendedState, State
from dronewrapper.msgs.sensor import BatteryState, Image, NavSatFix
from dronewrapper.msgs.std import Header
from dronewrapper.record.reader import read_bus
from dronewrapper.record.recorder import Recorder
from dronewrapper.record.ros2_bag import convert_to_ros2
from dronewrapper_ros2_codec import convert

T0 = 1_700_000_000.0


def _messages(i: int) -> dict[str, object]:
    t = T0 + i / 10
    image = Image(
        header=Header(stamp=t, frame_id="cam_frontal"),
        height=4,
        width=6,
        step=18,
        data=memoryview(bytes((i + k) % 256 for k in range(72))),
    )
    return {
        registry.STATE.key("drone"): State(
            header=Header(stamp=t),
            connected=True,
            armed=i % 2 == 1,
            mode="OFFBOARD",
            system_status=4,
        ),
        registry.EXTENDED_STATE.key("drone"): ExtendedState(
            header=Header(stamp=t), landed_state=1 + i % 2
        ),
        registry.LOCAL_POSE.key("drone"): PoseStamped(
            header=Header(stamp=t, frame_id="map"), pose=Pose(position=Point(x=i, y=-i, z=0.5))
        ),
        registry.VELOCITY_BODY.key("drone"): TwistStamped(
            header=Header(stamp=t, frame_id="base_link"),
            twist=Twist(linear=Vector3(x=0.25 * i), angular=Vector3(z=-0.5)),
        ),
        registry.GLOBAL_POSITION.key("drone"): NavSatFix(
            header=Header(stamp=t), latitude=47.0 + i, longitude=8.5, altitude=400.0
        ),
        registry.BATTERY.key("drone"): BatteryState(
            header=Header(stamp=t), voltage=12.5, percentage=0.75
        ),
        registry.IMAGE_RAW.key("drone", camera="cam_frontal"): image,
        registry.CONTROLLER_STATUS.key("drone"): ControllerStatus(header=Header(stamp=t)),
    }


def test_ros2_bag_reads_back_with_rosbags_every_message_equal(tmp_path):
    source, target = tmp_path / "ours.mcap", tmp_path / "ros2.mcap"
    with source.open("wb") as f, Recorder(f) as recorder:
        for i in range(5):
            for key, msg in _messages(i).items():
                recorder.write(key, codec.encode(msg), int((T0 + i / 10) * 1e9))
    written, skipped = convert_to_ros2(source, target)
    assert skipped == {registry.CONTROLLER_STATUS.key("drone"): 5}
    assert sum(written.values()) == 5 * 7

    expected = [m for m in read_bus(source) if m.key in written]
    typestore = get_typestore(Stores.ROS2_JAZZY)
    with AnyReader([target], default_typestore=typestore) as reader:
        got = [
            (c.topic, c.msgtype, t, reader.deserialize(raw, c.msgtype))
            for c, t, raw in reader.messages()
        ]
    assert len(got) == len(expected)
    for message, (topic, msgtype, log_time, theirs) in zip(expected, got, strict=True):
        ours = message.decode()
        assert topic == "/" + message.key and log_time == message.log_time_ns
        assert msgtype == convert.ROS_TYPES[type(ours)]
        assert _equal(convert.to_ros(ours), theirs), (topic, ours, theirs)


def test_foxglove_s_decoder_reads_the_ros2_bag(tmp_path):
    from mcap.reader import make_reader
    from mcap_ros2.decoder import DecoderFactory

    source, target = tmp_path / "ours.mcap", tmp_path / "ros2.mcap"
    with source.open("wb") as f, Recorder(f) as recorder:
        for key, msg in _messages(3).items():
            recorder.write(key, codec.encode(msg), int(T0 * 1e9))
    convert_to_ros2(source, target)
    with target.open("rb") as f:
        reader = make_reader(f, decoder_factories=[DecoderFactory()])
        assert reader.get_header().profile == "ros2"
        decoded = {c.topic: m for _, c, _, m in reader.iter_decoded_messages()}
    assert decoded["/drone/mavros/state"].mode == "OFFBOARD"
    assert decoded["/drone/mavros/local_position/pose"].pose.position.x == 3.0
    image = decoded["/drone/cam_frontal/image_raw"]
    assert (image.width, image.height, image.encoding, len(image.data)) == (6, 4, "bgr8", 72)


def _equal(ours: object, theirs: object) -> bool:
    """Field by field: our ROS 2 value against rosbags' message object (float32 fields to
    float32 precision, NaN equal to NaN)."""
    if isinstance(ours, dict):
        shared = [k for k in ours if hasattr(theirs, k)]  # our extensions have no ROS field
        return bool(shared) and all(_equal(ours[k], getattr(theirs, k)) for k in shared)
    if isinstance(ours, memoryview | bytes):
        return bytes(ours) == bytes(theirs)
    if isinstance(ours, list):
        return len(ours) == len(theirs) and all(
            _equal(a, b) for a, b in zip(ours, theirs, strict=True)
        )
    if isinstance(ours, float):
        return (math.isnan(ours) and math.isnan(theirs)) or math.isclose(
            ours, float(theirs), rel_tol=1e-6, abs_tol=1e-9
        )
    return ours == theirs
