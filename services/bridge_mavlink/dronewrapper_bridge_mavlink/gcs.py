"""The autopilot's MAVLink for a ground station (QGroundControl) beside the bridge, as MAVROS's
``gcs_url`` does: on a Jetson the bridge owns the autopilot's serial port, so a user's QGC
could not see the drone otherwise.

Frames from the autopilot are copied as they are to a UDP ground station (``gcs_url``) and,
optionally, to Zenoh (``{ns}/mavlink/from_autopilot``, for ``dronewrapper mavlink-forward`` on
a laptop); frames from the ground station go to the autopilot unchanged. The bridge's own
command acknowledgements are told apart by their target component (ours is not QGC's), so a
ground station's commands never satisfy or disturb the bridge's waiting calls.
"""

from __future__ import annotations

import ipaddress
import logging
import select
import socket
import threading
from collections.abc import Callable

from dronewrapper.msgs.mavlink import MavlinkFrames
from dronewrapper.msgs.std import Header
from dronewrapper.runtime.clock import REAL, Clock

log = logging.getLogger("bridge_mavlink")

BATCH_S = 0.02
"""Frames for Zenoh are sent in batches at most this old (s)."""
MAX_DATAGRAM = 2048


def parse_gcs_url(url: str) -> tuple[str, int]:
    """``udp:HOST:PORT`` -> (HOST, PORT): the ground station listens there (QGC: 14550).

    Raises:
        ValueError: another scheme, a missing or bad port.
    """
    scheme, _, rest = url.partition(":")
    host, _, port = rest.rpartition(":")
    if scheme != "udp" or not host or not port.isdigit() or not 0 < int(port) < 65536:
        raise ValueError(f"gcs_url must be udp:HOST:PORT (e.g. udp:127.0.0.1:14550), got {url!r}")
    return host, int(port)


def is_loopback(host: str) -> bool:
    """True for a loopback address or ``localhost``."""
    if host == "localhost":
        return True
    try:
        return ipaddress.ip_address(host).is_loopback
    except ValueError:
        return False


class GcsForwarder:
    """Copies frames between the autopilot link and a ground station (UDP and/or Zenoh).

    Args:
        to_autopilot: writes raw frames to the autopilot link (thread-safe).
        gcs_address: (host, port) of a UDP ground station, or None.
        publish: sends a MavlinkFrames batch on Zenoh, or None.
        clock: the node's clock (batch ages, their stamps, the wait without a UDP station).
    """

    def __init__(
        self,
        to_autopilot: Callable[[bytes], None],
        gcs_address: tuple[str, int] | None,
        publish: Callable[[MavlinkFrames], None] | None = None,
        *,
        clock: Clock = REAL,
    ) -> None:
        self._to_autopilot = to_autopilot
        self._gcs = gcs_address
        self._publish = publish
        self._clock = clock
        self._sock: socket.socket | None = None
        if gcs_address is not None:
            self._sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
            self._sock.bind(("127.0.0.1" if is_loopback(gcs_address[0]) else "0.0.0.0", 0))
        self._batch: list[bytes] = []
        self._batch_since = 0.0
        self._lock = threading.Lock()
        self.to_gcs = self.from_gcs = self.errors = 0

    def from_autopilot(self, frame: bytes) -> None:
        """A frame the autopilot sent: to the UDP ground station now, to Zenoh in a batch."""
        if self._sock is not None and self._gcs is not None:
            try:
                self._sock.sendto(frame, self._gcs)
                self.to_gcs += 1
            except OSError as exc:  # no ground station listening yet: ICMP refusals
                self.errors += 1
                log.debug("to GCS: %s", exc)
        if self._publish is not None:
            with self._lock:
                if not self._batch:
                    self._batch_since = self._clock.monotonic()
                self._batch.append(frame)

    def from_zenoh(self, frames: MavlinkFrames) -> None:
        """Frames a remote ground station sent over Zenoh: to the autopilot."""
        for frame in frames.frames[:256]:
            self._write(frame)

    def _write(self, frame: bytes) -> None:
        try:
            self._to_autopilot(frame)
            self.from_gcs += 1
        except OSError as exc:
            self.errors += 1
            log.debug("to autopilot: %s", exc)

    def flush(self, now: float) -> None:
        """Publish the Zenoh batch if its oldest frame is BATCH_S old."""
        if self._publish is None:
            return
        with self._lock:
            if not self._batch or now - self._batch_since < BATCH_S:
                return
            batch, self._batch = self._batch, []
        self._publish(MavlinkFrames(header=Header(stamp=self._clock.time()), frames=batch))

    def run(self, stop: threading.Event) -> None:
        """Read the UDP ground station's frames and flush Zenoh batches until ``stop``."""
        while not stop.is_set():
            if self._sock is None:
                self._clock.wait(stop, BATCH_S)
            else:
                readable, _, _ = select.select([self._sock], [], [], BATCH_S)
                if readable:
                    try:
                        data, _ = self._sock.recvfrom(MAX_DATAGRAM)
                    except OSError:
                        data = b""
                    if data:
                        self._write(data)
            self.flush(self._clock.monotonic())

    def close(self) -> None:
        if self._sock is not None:
            self._sock.close()
