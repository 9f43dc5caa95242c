"""Our recordings as ROS 2 bags: MCAP with ``ros2msg`` schemas and CDR messages.

What ``ros2 bag play``, Foxglove and the rosbags reader open: profile ``ros2``, one schema per ROS 2
type (its ``.msg`` text and its dependencies', :func:`dronewrapper_ros2_codec.interfaces.msg_text`),
one channel per key named as the gateway names it (``/drone/mavros/state``), message encoding
``cdr``. Keys without a ROS 2 type (detections, controller status, the raw MAVLink) are left out and
counted. Log and publish times are the recording's.
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Iterable
from pathlib import Path
from typing import BinaryIO

from mcap.writer import CompressionType, Writer

from dronewrapper.record.reader import BusMessage, read_bus
from dronewrapper_ros2_codec import cdr
from dronewrapper_ros2_codec.convert import ROS_TYPES, to_ros
from dronewrapper_ros2_codec.interfaces import msg_text

COMPRESSION = {
    "zstd": CompressionType.ZSTD,
    "lz4": CompressionType.LZ4,
    "none": CompressionType.NONE,
}


def ros2_topic(key: str) -> str:
    """The ROS 2 name of one of our keys (``drone/mavros/state`` -> ``/drone/mavros/state``)."""
    return "/" + key


def write_ros2_bag(
    messages: Iterable[BusMessage], out: BinaryIO, *, compression: str = "zstd"
) -> tuple[Counter[str], Counter[str]]:
    """Write ``messages`` as a ROS 2 MCAP to ``out``; (written, skipped) counts by key."""
    writer = Writer(out, compression=COMPRESSION[compression])
    writer.start(profile="ros2", library="dronewrapper")
    schemas: dict[str, int] = {}
    channels: dict[str, int] = {}
    written: Counter[str] = Counter()
    skipped: Counter[str] = Counter()
    for message in messages:
        topic = message.topic
        ros_type = ROS_TYPES.get(topic.type) if topic is not None else None
        if ros_type is None:
            skipped[message.key] += 1
            continue
        if ros_type not in schemas:
            schemas[ros_type] = writer.register_schema(
                name=ros_type, encoding="ros2msg", data=msg_text(ros_type).encode()
            )
        if message.key not in channels:
            channels[message.key] = writer.register_channel(
                topic=ros2_topic(message.key),
                message_encoding="cdr",
                schema_id=schemas[ros_type],
            )
        data = cdr.encode(ros_type, to_ros(message.decode()))
        writer.add_message(
            channels[message.key],
            log_time=message.log_time_ns,
            publish_time=message.publish_time_ns,
            data=data,
            sequence=written[message.key],
        )
        written[message.key] += 1
    writer.finish()
    return written, skipped


def convert_to_ros2(
    source: str | Path, target: str | Path, *, compression: str = "zstd"
) -> tuple[Counter[str], Counter[str]]:
    """Convert our recording ``source`` to the ROS 2 bag ``target`` (one ``.mcap`` file)."""
    with Path(target).open("wb") as out:
        return write_ros2_bag(read_bus(source), out, compression=compression)
