"""The bus to MCAP: one channel per key, schemas in the file, chunked, compressed, crash-safe.

For each key a message arrives on, the file gets:

- the raw MessagePack on a channel named exactly like the key (message encoding ``msgpack``,
  its JSON schema stored for reference), which is what the replayer publishes again. Camera
  images are the exception: their pixels are stored once, in the Foxglove image view, from which
  the replayer rebuilds the bus message (channel metadata ``raw: view`` or ``raw: jpeg``);
- the Foxglove views of :mod:`.views` (``/`` + key, ``/tf``, annotations, the map fix).

Keys the registry does not know keep their raw bytes only. Crash safety: the writer closes the
current chunk and flushes the file at least every ``flush_period_s`` seconds, so a recorder
killed by SIGKILL leaves a file whose complete chunks :mod:`.reader` (and ``mcap recover``)
read; a clean :meth:`Recorder.close` also writes the summary and footer.

Pure of I/O apart from the output stream: samples and their receive times are passed in.
"""

from __future__ import annotations

import logging
import time
from collections import Counter
from collections.abc import Callable
from typing import Any, BinaryIO

import msgspec
from mcap.writer import CompressionType, Writer

from dronewrapper.errors import DroneError
from dronewrapper.msgs import codec, registry
from dronewrapper.msgs.sensor import CompressedImage, Image
from dronewrapper.record.views import SchemaSpec, View, message_schema, views

log = logging.getLogger("dronewrapper.record")

PROFILE = "dronewrapper"
RAW_ENCODING = "msgpack"
"""Message encoding of the raw bus channels (MessagePack maps)."""

CHUNK_SIZE = 1 << 20
"""Uncompressed bytes per chunk before the writer closes it (B)."""


def _stamp_ns(msg: Any, fallback: int) -> int:
    header = getattr(msg, "header", None)
    stamp = getattr(header, "stamp", 0.0)
    if isinstance(stamp, float) and 0.0 < stamp < 1e11:
        return int(stamp * 1e9)
    return fallback


class Recorder:
    """Writes bus samples into an open binary stream as MCAP (use as a context manager).

    Args:
        output: a writable binary stream (a file opened ``wb``).
        jpeg_quality: compress raw camera images to JPEG at this quality (1..100); None keeps
            them raw.
        compression: ``zstd``, ``lz4`` or ``none`` (per chunk).
        flush_period_s: longest time a message stays unflushed (s); bounds what SIGKILL loses.
        clock: monotonic seconds, for the flush period (injected in tests).
    """

    def __init__(
        self,
        output: BinaryIO,
        *,
        jpeg_quality: int | None = None,
        compression: str = "zstd",
        flush_period_s: float = 1.0,
        chunk_size: int = CHUNK_SIZE,
        clock: Callable[[], float] = time.monotonic,
    ) -> None:
        if jpeg_quality is not None and not 1 <= jpeg_quality <= 100:
            raise ValueError(f"jpeg_quality must be 1..100, got {jpeg_quality}")
        if not flush_period_s > 0:
            raise ValueError(f"flush_period_s must be > 0, got {flush_period_s}")
        kinds = {"zstd": CompressionType.ZSTD, "lz4": CompressionType.LZ4}
        kinds["none"] = CompressionType.NONE
        if compression not in kinds:
            raise ValueError(f"compression must be one of {', '.join(kinds)}, got {compression!r}")
        self.jpeg_quality = jpeg_quality
        self.counts: Counter[str] = Counter()  # bus messages per key
        self.decode_errors: Counter[str] = Counter()
        self.view_errors: Counter[str] = Counter()
        self.bytes_in = 0
        self._output = output
        self._writer = Writer(output, chunk_size=chunk_size, compression=kinds[compression])
        self._writer.start(profile=PROFILE, library="dronewrapper")
        self._schemas: dict[SchemaSpec, int] = {}
        self._channels: dict[tuple[str, str, str], int] = {}
        self._sequence: Counter[int] = Counter()
        self._flush_period = flush_period_s
        self._clock = clock
        self._last_flush = clock()
        self._closed = False

    def __enter__(self) -> Recorder:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def _schema_id(self, schema: SchemaSpec | None) -> int:
        if schema is None:
            return 0
        sid = self._schemas.get(schema)
        if sid is None:
            sid = self._writer.register_schema(schema.name, schema.encoding, schema.data)
            self._schemas[schema] = sid
        return sid

    def _channel_id(
        self, topic: str, encoding: str, schema: SchemaSpec | None, metadata: dict[str, str]
    ) -> int:
        ident = (topic, encoding, schema.name if schema else "")
        cid = self._channels.get(ident)
        if cid is None:
            cid = self._writer.register_channel(
                topic, encoding, self._schema_id(schema), metadata=metadata
            )
            self._channels[ident] = cid
        return cid

    def _add(self, cid: int, log_ns: int, pub_ns: int, data: bytes) -> None:
        self._sequence[cid] += 1
        self._writer.add_message(cid, log_ns, data, pub_ns, sequence=self._sequence[cid])

    def write(self, key: str, payload: bytes, log_time_ns: int) -> None:
        """Record one sample received on ``key`` at ``log_time_ns`` (ns since the epoch)."""
        if self._closed:
            raise RuntimeError("recorder is closed")
        self.counts[key] += 1
        self.bytes_in += len(payload)
        topic = registry.topic_for_key(key)
        msg = None
        if topic is not None:
            try:
                msg = codec.decode(topic.type, payload)
            except (msgspec.DecodeError, msgspec.ValidationError) as exc:
                self.decode_errors[key] += 1
                if self.decode_errors[key] == 1:
                    log.warning("%s: undecodable %s kept raw: %s", key, topic.type.__name__, exc)
        pub_ns = _stamp_ns(msg, log_time_ns)
        out: list[View] | None = None
        if topic is not None and msg is not None:
            try:
                out = views(key, topic, msg, jpeg_quality=self.jpeg_quality)
            except (ValueError, DroneError) as exc:  # e.g. an image shorter than its size
                self.view_errors[key] += 1
                if self.view_errors[key] == 1:
                    log.warning("%s: no Foxglove view (raw kept): %s", key, exc)
        if topic is None or msg is None or out is None:
            schema = None
            if topic is not None:
                schema = message_schema(topic.type)  # type: ignore[arg-type]  # mypy: type[Any] not Hashable
            meta = {"key": key, "type": topic.type.__name__ if topic is not None else ""}
            cid = self._channel_id(key, RAW_ENCODING, schema, meta)
            self._add(cid, log_time_ns, pub_ns, payload)
        else:
            self._write_views(key, topic, msg, payload, out, log_time_ns, pub_ns)
        if self._clock() - self._last_flush >= self._flush_period:
            self.flush()

    def _write_views(
        self,
        key: str,
        topic: registry.Topic[Any],
        msg: Any,
        payload: bytes,
        out: list[View],
        log_ns: int,
        pub_ns: int,
    ) -> None:
        type_name = topic.type.__name__
        is_image = isinstance(msg, Image | CompressedImage)
        if not is_image:
            meta = {"key": key, "type": type_name}
            schema = message_schema(topic.type)  # type: ignore[arg-type]  # mypy: type[Any] not Hashable
            cid = self._channel_id(key, RAW_ENCODING, schema, meta)
            self._add(cid, log_ns, pub_ns, payload)
        for i, view in enumerate(out):
            meta = {}
            if i == 0:
                meta = {"key": key, "type": type_name}
                if is_image:
                    jpeg = isinstance(msg, Image) and self.jpeg_quality is not None
                    meta["raw"] = "jpeg" if jpeg else "view"
            cid = self._channel_id(view.topic, view.message_encoding, view.schema, meta)
            self._add(cid, log_ns, pub_ns, view.data)

    def flush(self) -> None:
        """Close the current chunk and push it to the OS (survives a SIGKILL from here on)."""
        self._writer.flush()
        self._last_flush = self._clock()

    def close(self) -> None:
        """Write the last chunk, the summary and the footer (idempotent)."""
        if self._closed:
            return
        self._closed = True
        self._writer.finish()
        self._output.flush()
