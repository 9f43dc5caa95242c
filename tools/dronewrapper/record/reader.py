"""A recording back as bus messages, and its summary; cut files (a killed recorder) included.

The file is read sequentially (messages come in the order they were received), so a file with
no summary or footer reads up to its last complete chunk and says it was ``truncated``.

Bus messages come back as the MessagePack the bus carried: raw channels as stored, camera
frames rebuilt from their Foxglove image view (JPEG-stored raw frames decoded back to ``bgr8``,
lossy).
"""

from __future__ import annotations

import logging
import struct
from collections.abc import Iterable, Iterator
from dataclasses import dataclass, field
from functools import cache
from pathlib import Path
from typing import Any

import zenoh
from mcap.exceptions import McapError
from mcap.records import Channel, Message, Schema
from mcap.stream_reader import StreamReader

from dronewrapper.errors import DroneError
from dronewrapper.msgs import codec, registry
from dronewrapper.msgs.sensor import CompressedImage, Image
from dronewrapper.msgs.std import Header
from dronewrapper.record.recorder import RAW_ENCODING

log = logging.getLogger("dronewrapper.record")


@dataclass(frozen=True)
class BusMessage:
    """One recorded bus message: key, payload (MessagePack), times in ns since the epoch."""

    key: str
    payload: bytes
    log_time_ns: int
    publish_time_ns: int

    @property
    def topic(self) -> registry.Topic[Any] | None:
        return registry.topic_for_key(self.key)

    def decode(self) -> Any:
        """The payload decoded with the registry's type for the key."""
        topic = self.topic
        if topic is None:
            raise ValueError(f"{self.key} is not a registered key")
        return codec.decode(topic.type, self.payload)


@dataclass
class ChannelInfo:
    """What :func:`summarize` says of one channel."""

    topic: str
    message_encoding: str
    schema: str
    count: int = 0
    bytes: int = 0
    first_ns: int = 0
    last_ns: int = 0

    @property
    def rate_hz(self) -> float:
        span = (self.last_ns - self.first_ns) / 1e9
        return (self.count - 1) / span if self.count > 1 and span > 0 else 0.0


@dataclass
class RecordingInfo:
    """Channels, counts, rates and duration of a recording."""

    path: str
    size: int
    truncated: bool = False
    channels: list[ChannelInfo] = field(default_factory=list)

    @property
    def count(self) -> int:
        return sum(c.count for c in self.channels)

    @property
    def start_ns(self) -> int:
        return min((c.first_ns for c in self.channels if c.count), default=0)

    @property
    def end_ns(self) -> int:
        return max((c.last_ns for c in self.channels if c.count), default=0)

    @property
    def duration_s(self) -> float:
        return (self.end_ns - self.start_ns) / 1e9

    def text(self) -> str:
        """The summary as a table for people."""
        lines = [
            f"file:     {self.path} ({self.size / 1e6:.2f} MB)"
            + ("  [cut: no summary, read to the last complete chunk]" if self.truncated else ""),
            f"duration: {self.duration_s:.2f} s, {self.count} messages",
            f"{'topic':58} {'encoding':9} {'schema':28} {'count':>6} {'Hz':>6} {'KB':>8}",
        ]
        for c in sorted(self.channels, key=lambda c: c.topic):
            lines.append(
                f"{c.topic:58} {c.message_encoding:9} {c.schema:28} {c.count:6d} "
                f"{c.rate_hz:6.1f} {c.bytes / 1e3:8.1f}"
            )
        return "\n".join(lines)


@dataclass
class _Records:
    """Schemas, channels and messages of a file in order; ``truncated`` once read to its end."""

    path: Path
    schemas: dict[int, Schema] = field(default_factory=dict)
    channels: dict[int, Channel] = field(default_factory=dict)
    truncated: bool = False

    def messages(self) -> Iterator[tuple[Channel, Message]]:
        with self.path.open("rb") as f:
            reader = StreamReader(f, record_size_limit=1 << 30)
            try:
                for record in reader.records:
                    if isinstance(record, Schema):
                        self.schemas[record.id] = record
                    elif isinstance(record, Channel):
                        self.channels[record.id] = record
                    elif isinstance(record, Message):
                        channel = self.channels.get(record.channel_id)
                        if channel is not None:
                            yield channel, record
            except (McapError, struct.error, EOFError, ValueError):
                self.truncated = True  # cut inside a record: what came before is complete


def summarize(path: str | Path) -> RecordingInfo:
    """Channels, counts, rates and duration of a recording (complete or cut)."""
    path = Path(path)
    records = _Records(path)
    by_channel: dict[int, ChannelInfo] = {}
    for channel, message in records.messages():
        info = by_channel.get(channel.id)
        if info is None:
            schema = records.schemas.get(channel.schema_id)
            name = schema.name if schema else ""
            info = ChannelInfo(channel.topic, channel.message_encoding, name)
            info.first_ns = message.log_time
            by_channel[channel.id] = info
        info.count += 1
        info.bytes += len(message.data)
        info.last_ns = message.log_time
    return RecordingInfo(
        str(path), path.stat().st_size, records.truncated, list(by_channel.values())
    )


@cache
def _protobuf_class(schema_name: str, schema_data: bytes) -> Any:
    from google.protobuf import descriptor_pb2, message_factory

    files = descriptor_pb2.FileDescriptorSet.FromString(schema_data)
    return message_factory.GetMessages(files.file)[schema_name]


def _stamp(ts: Any) -> float:
    return ts.seconds + ts.nanos * 1e-9


def image_from_view(schema: Schema, data: bytes, raw: str) -> Image | CompressedImage:
    """Rebuild the bus image from its Foxglove view (``raw``: ``view`` or ``jpeg``)."""
    proto = _protobuf_class(schema.name, bytes(schema.data)).FromString(data)
    header = Header(stamp=_stamp(proto.timestamp), frame_id=proto.frame_id)
    if schema.name == "foxglove.RawImage":
        return Image(
            header=header,
            height=proto.height,
            width=proto.width,
            encoding=proto.encoding,
            step=proto.step,
            data=proto.data,
        )
    if raw == "jpeg":  # a raw frame stored as JPEG: back to bgr8 (lossy)
        from dronewrapper.images import jpeg_decoder

        cv2 = jpeg_decoder()
        import numpy as np

        bgr = cv2.imdecode(np.frombuffer(proto.data, np.uint8), cv2.IMREAD_COLOR)
        if bgr is None:
            raise ValueError(f"undecodable JPEG frame on {header.frame_id or 'a camera'}")
        height, width = bgr.shape[:2]
        return Image(header=header, height=height, width=width, step=width * 3, data=bgr.tobytes())
    return CompressedImage(header=header, format=proto.format, data=proto.data)


def _selected(key: str, keys: list[zenoh.KeyExpr] | None) -> bool:
    if keys is None:
        return True
    ke = zenoh.KeyExpr(key)
    return any(k.intersects(ke) for k in keys)


def read_bus(
    path: str | Path, keys: Iterable[str] | None = None, *, start_ns: int = 0
) -> Iterator[BusMessage]:
    """The recorded bus messages in order, optionally only keys matching ``keys``.

    ``start_ns`` skips messages logged before that time (ns since the epoch).
    """
    wanted = [zenoh.KeyExpr(k) for k in keys] if keys else None
    records = _Records(Path(path))
    for channel, message in records.messages():
        if message.log_time < start_ns:
            continue
        meta = channel.metadata
        key = meta.get("key", "")
        if channel.message_encoding == RAW_ENCODING:
            payload = bytes(message.data)
        elif meta.get("raw") in ("view", "jpeg"):
            schema = records.schemas[channel.schema_id]
            try:
                payload = codec.encode(image_from_view(schema, message.data, meta["raw"]))
            except (ValueError, DroneError) as exc:  # a frame damaged in the file: skipped
                log.warning("%s at %d ns: frame skipped: %s", key, message.log_time, exc)
                continue
        else:
            continue  # a derived view: not on the bus
        if key and _selected(key, wanted):
            yield BusMessage(key, payload, message.log_time, message.publish_time)
