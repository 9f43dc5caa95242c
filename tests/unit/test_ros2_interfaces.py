"""The project's ROS 2 interfaces against independent implementations: RIHS01 hashes and CDR
bytes against rosbags (ROS 2 Jazzy's own definitions where rosbags ships them, the upstream
mavros_msgs text otherwise), service hashes against zenoh-ros2-sdk, and published golden
hashes."""

from __future__ import annotations

import math
from pathlib import Path

import pytest
from rosbags.typesys import Stores, get_types_from_msg, get_typestore

from dronewrapper.msgs.geometry import Point, Pose, PoseStamped, Quaternion, Twist, TwistStamped
from dronewrapper.msgs.mavros import (
    CommandTOL,
    ExtendedState,
    PositionTarget,
    State,
)
from dronewrapper.msgs.sensor import BatteryState, CompressedImage, Image, NavSatFix
from dronewrapper.msgs.std import Header
from dronewrapper_ros2_codec import cdr, convert, interfaces
from dronewrapper_ros2_codec.typehash import type_hash

UPSTREAM = Path(__file__).resolve().parents[1] / "data" / "ros2_interfaces"
JAZZY_TYPES = [
    "builtin_interfaces/msg/Time",
    "std_msgs/msg/Header",
    "geometry_msgs/msg/PoseStamped",
    "geometry_msgs/msg/TwistStamped",
    "sensor_msgs/msg/NavSatFix",
    "sensor_msgs/msg/BatteryState",
    "sensor_msgs/msg/Image",
    "sensor_msgs/msg/CompressedImage",
]
MAVROS_TYPES = [
    "mavros_msgs/msg/State",
    "mavros_msgs/msg/ExtendedState",
    "mavros_msgs/msg/PositionTarget",
    "mavros_msgs/msg/ParamValue",
]


@pytest.fixture(scope="module")
def store():
    """rosbags' ROS 2 Jazzy type store plus mavros_msgs from the upstream .msg text."""
    typestore = get_typestore(Stores.ROS2_JAZZY)
    types = {}
    for name in MAVROS_TYPES:
        path = UPSTREAM / f"{name}.msg"
        types.update(get_types_from_msg(path.read_text(), name))
    typestore.register(types)
    return typestore


@pytest.mark.parametrize("name", JAZZY_TYPES + MAVROS_TYPES)
def test_type_hash_equals_rosbags(store, name):
    assert type_hash(name) == store.hash_rihs01(name)


def test_golden_hashes_from_ros2():
    # rmw_zenoh's docs/design.md example key, and the Jazzy hash of ServiceEventInfo (whose
    # char[16] is uint8[16] after rosidl's .msg -> .idl step)
    assert interfaces.parse("std_msgs/msg/String", "string data").fields[0].base == "string"
    saved = dict(interfaces.MESSAGES), dict(interfaces.SERVICES)
    try:
        interfaces.MESSAGES["std_msgs/msg/String"] = "string data\n"
        interfaces.SERVICES["std_srvs/srv/SetBool"] = (
            "bool data\n",
            "bool success\nstring message\n",
        )
        type_hash.cache_clear()
        interfaces.message.cache_clear()
        assert type_hash("std_msgs/msg/String") == (
            "RIHS01_df668c740482bbd48fb39d76a70dfd4bd59db1288021743503259e948f6b1a18"
        )
        assert type_hash("std_srvs/srv/SetBool") == (
            "RIHS01_abe9e4bb6b41b40e6789712c00ec8871923e089af3f667a79992a428cff2da0a"
        )
    finally:
        interfaces.MESSAGES.clear()
        interfaces.MESSAGES.update(saved[0])
        interfaces.SERVICES.clear()
        interfaces.SERVICES.update(saved[1])
        type_hash.cache_clear()
        interfaces.message.cache_clear()
    assert type_hash("service_msgs/msg/ServiceEventInfo") == (
        "RIHS01_41bcbbe07a75c9b52bc96bfd5c24d7f0fc0a08c0cb7921b3373c5732345a6f45"
    )


def test_upstream_text_parses_to_our_fields():
    for name in MAVROS_TYPES:
        upstream = interfaces.parse(name, (UPSTREAM / f"{name}.msg").read_text())
        assert upstream == interfaces.message(name)


SAMPLES = [
    State(
        header=Header(stamp=1700000000.25, frame_id="map"),
        connected=True,
        armed=True,
        guided=True,
        mode="OFFBOARD",
        system_status=4,
        autopilot="px4",
        commander="alice",
    ),
    ExtendedState(header=Header(stamp=2.5), landed_state=2),
    PoseStamped(
        header=Header(stamp=1700000000.123456789, frame_id="map"),
        pose=Pose(
            position=Point(x=1.0, y=-2.0, z=3.5),
            orientation=Quaternion(x=0.0, y=0.0, z=0.38268343, w=0.92387953),
        ),
    ),
    TwistStamped(
        header=Header(stamp=3.0, frame_id="base_link"),
        twist=Twist(linear=Point(x=1.0, y=2.0, z=3.0), angular=Point(z=0.5)),
    ),
    NavSatFix(
        header=Header(stamp=4.0),
        latitude=47.39,
        longitude=8.54,
        altitude=488.0,
        position_covariance=[float(i) for i in range(9)],
    ),
    BatteryState(header=Header(stamp=5.0), voltage=12.4, current=3.5, percentage=0.87),
    Image(
        header=Header(stamp=6.0, frame_id="cam_frontal"),
        height=2,
        width=3,
        step=9,
        data=memoryview(bytes(range(18))),
    ),
    CompressedImage(header=Header(stamp=7.0), format="jpeg", data=memoryview(b"\xff\xd8jpeg")),
    PositionTarget(
        header=Header(stamp=8.0),
        coordinate_frame=8,
        type_mask=1991,
        velocity=Point(x=0.5),
        yaw_rate=0.25,
    ),
]


@pytest.mark.parametrize("msg", SAMPLES, ids=lambda m: type(m).__name__)
def test_cdr_bytes_equal_rosbags(store, msg):
    name = convert.ROS_TYPES[type(msg)]
    ours = cdr.encode(name, convert.to_ros(msg))
    theirs = store.deserialize_cdr(ours, name)
    assert bytes(store.serialize_cdr(theirs, name)) == ours
    assert theirs.header.stamp.sec == math.floor(msg.header.stamp)
    back = convert.from_ros(type(msg), cdr.decode(name, ours))
    assert type(back) is type(msg)
    assert cdr.encode(name, convert.to_ros(back)) == ours  # our side reads what it wrote


def test_state_extensions_stay_ours(store):
    msg = SAMPLES[0]
    theirs = store.deserialize_cdr(
        cdr.encode("mavros_msgs/msg/State", convert.to_ros(msg)), "mavros_msgs/msg/State"
    )
    assert (theirs.connected, theirs.armed, theirs.mode, theirs.system_status) == (
        True,
        True,
        "OFFBOARD",
        4,
    )
    assert not hasattr(theirs, "commander")


def test_requests_from_rosbags_decode(store):
    typestore = get_typestore(Stores.EMPTY)
    request, _ = (UPSTREAM / "mavros_msgs/srv/CommandTOL.srv").read_text().split("---")
    theirs = "mavros_msgs/msg/CommandTOLRequest"  # rosbags keeps messages only: same bytes
    typestore.register(get_types_from_msg(request, theirs))
    cls = typestore.types[theirs]
    raw = bytes(
        typestore.serialize_cdr(
            cls(min_pitch=0.0, yaw=math.nan, latitude=math.nan, longitude=math.nan, altitude=2.5),
            theirs,
        )
    )
    value = cdr.decode("mavros_msgs/srv/CommandTOL_Request", raw)
    ours = convert.request_of(CommandTOL, value)
    assert ours.altitude == 2.5 and math.isnan(ours.yaw)


@pytest.mark.parametrize(
    "payload",
    [b"", b"\x00\x01\x00\x00", b"\x00\x01\x00\x00\x01\x00", b"\x01\x01\x00\x00" + bytes(200)],
)
def test_garbage_is_a_cdr_error(payload):
    with pytest.raises(cdr.CdrError):
        cdr.decode("mavros_msgs/msg/PositionTarget", payload)


def test_result_without_ack_is_failed_in_uint8():
    from dronewrapper.msgs.mavros import CommandBoolResult

    assert convert.response_of(CommandBoolResult(success=False, result=-1)) == {
        "success": False,
        "result": 4,
    }


def test_msg_text_is_the_ros2msg_schema(store):
    text = interfaces.msg_text("geometry_msgs/msg/PoseStamped")
    assert text.startswith("std_msgs/Header header\ngeometry_msgs/Pose pose\n")
    assert "\nMSG: builtin_interfaces/Time\nint32 sec\nuint32 nanosec\n" in text


def test_upstream_mavros_msgs_files_are_the_recorded_ones():
    import hashlib
    import re

    readme = (UPSTREAM / "README.md").read_text()
    recorded = re.findall(r"([0-9a-f]{64})  ((?:msg|srv)/\w+\.(?:msg|srv))", readme)
    assert len(recorded) == 9
    for digest, name in recorded:
        data = (UPSTREAM / "mavros_msgs" / name).read_bytes()
        assert hashlib.sha256(data).hexdigest() == digest, name
