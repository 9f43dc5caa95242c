"""The live bus served to Foxglove: the ``foxglove-sdk`` WebSocket server, the recorder's schemas.

Each sample on the subscribed key expressions is decoded with the registry's type and turned into
the same views the recorder writes (:mod:`.views`); a channel is advertised the first time its
topic appears. Samples are converted on the caller's thread from a bounded queue (full: dropped
and counted), so a slow viewer never holds up the bus. Raw camera frames can be JPEG-compressed
on the way (a WebSocket to a laptop is no place for raw video).
"""

from __future__ import annotations

import logging
import queue
import threading
import time
from collections import Counter
from collections.abc import Sequence
from dataclasses import dataclass, field

import foxglove
import msgspec
import zenoh

from dronewrapper.errors import DroneError
from dronewrapper.msgs import codec, registry
from dronewrapper.record.pump import Queued, pump
from dronewrapper.record.views import View, views

log = logging.getLogger("dronewrapper.foxglove")

DEFAULT_PORT = 8765
QUEUE_SIZE = 256


@dataclass
class LiveStats:
    """Samples received, views sent, drops and undecodable samples."""

    received: int = 0
    sent: int = 0
    dropped: int = 0
    decode_errors: Counter[str] = field(default_factory=Counter)


class FoxgloveBridge:
    """Foxglove channels fed from bus messages (use as a context manager).

    Args:
        host, port: where the WebSocket server listens (loopback by default; port 0 picks one).
        jpeg_quality: compress raw camera frames to JPEG (1..100); None sends them raw.
    """

    def __init__(
        self, *, host: str = "127.0.0.1", port: int = DEFAULT_PORT, jpeg_quality: int | None = 80
    ) -> None:
        if jpeg_quality is not None and not 1 <= jpeg_quality <= 100:
            raise ValueError(f"jpeg_quality must be 1..100, got {jpeg_quality}")
        self.jpeg_quality = jpeg_quality
        self.stats = LiveStats()
        self.context = foxglove.Context()
        self.server = foxglove.start_server(
            name="dronewrapper", host=host, port=port, context=self.context
        )
        self._channels: dict[str, foxglove.Channel] = {}

    @property
    def port(self) -> int:
        return self.server.port

    def __enter__(self) -> FoxgloveBridge:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def _channel(self, view: View) -> foxglove.Channel:
        channel = self._channels.get(view.topic)
        if channel is None:
            schema = foxglove.Schema(
                name=view.schema.name, encoding=view.schema.encoding, data=view.schema.data
            )
            channel = foxglove.Channel(
                view.topic,
                schema=schema,
                message_encoding=view.message_encoding,
                context=self.context,
            )
            self._channels[view.topic] = channel
        return channel

    def publish(self, key: str, payload: bytes, log_time_ns: int) -> None:
        """Send the views of one bus sample to the connected viewers."""
        topic = registry.topic_for_key(key)
        if topic is None:
            return
        try:
            msg = codec.decode(topic.type, payload)
        except (msgspec.DecodeError, msgspec.ValidationError) as exc:
            self.stats.decode_errors[key] += 1
            if self.stats.decode_errors[key] == 1:
                log.warning("%s: undecodable %s skipped: %s", key, topic.type.__name__, exc)
            return
        try:
            out = views(key, topic, msg, jpeg_quality=self.jpeg_quality)
        except (ValueError, DroneError) as exc:  # e.g. an image shorter than its size
            self.stats.decode_errors[key] += 1
            if self.stats.decode_errors[key] == 1:
                log.warning("%s: cannot show this %s: %s", key, topic.type.__name__, exc)
            return
        for view in out:
            self._channel(view).log(view.data, log_time=log_time_ns)
            self.stats.sent += 1

    def close(self) -> None:
        self.server.stop()


def serve(
    session: zenoh.Session,
    keyexprs: Sequence[str],
    bridge: FoxgloveBridge,
    stop: threading.Event,
    *,
    duration: float = 0.0,
) -> LiveStats:
    """Feed ``bridge`` from ``keyexprs`` until ``stop`` or ``duration`` s (0: no limit)."""
    samples: queue.Queue[Queued] = queue.Queue(QUEUE_SIZE)
    stats = bridge.stats

    def on_sample(sample: zenoh.Sample) -> None:
        stats.received += 1
        try:
            samples.put_nowait((str(sample.key_expr), sample.payload.to_bytes(), time.time_ns()))
        except queue.Full:
            stats.dropped += 1

    pump(session, keyexprs, on_sample, samples, bridge.publish, stop, duration)
    return stats
