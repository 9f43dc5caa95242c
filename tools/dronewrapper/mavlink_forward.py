"""``dronewrapper mavlink-forward``: a drone's MAVLink over Zenoh as a local UDP link for
QGroundControl on a laptop.

The drone's bridge runs with ``gcs_over_zenoh: true``; this process subscribes to
``{ns}/mavlink/from_autopilot`` and sends each frame to QGC's UDP port (14550 by default, which
QGC listens on); what QGC answers (to this process's port) is published on
``{ns}/mavlink/to_autopilot``. Loopback by default; QGC sees the autopilot as if it were wired.
"""

from __future__ import annotations

import logging
import select
import socket
import threading

from dronewrapper.msgs.mavlink import MavlinkFrames
from dronewrapper.msgs.registry import MAVLINK_FROM_AUTOPILOT, MAVLINK_TO_AUTOPILOT
from dronewrapper.msgs.std import Header
from dronewrapper.runtime.node import Node
from dronewrapper.runtime.ports import Ports

log = logging.getLogger("mavlink-forward")

PORTS = Ports(
    "mavlink_forward", publishes=(MAVLINK_TO_AUTOPILOT,), subscribes=(MAVLINK_FROM_AUTOPILOT,)
)
"""What this process publishes and subscribes to (:mod:`dronewrapper.runtime.ports`)."""

MAX_DATAGRAM = 2048


class UdpGroundStation:
    """The UDP side: frames to QGC's address, QGC's datagrams back (from our own port)."""

    def __init__(self, qgc: tuple[str, int]) -> None:
        self.qgc = qgc
        self.sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self.sock.bind((qgc[0], 0))
        self.sent = self.received = 0

    def send(self, frames: MavlinkFrames) -> None:
        for frame in frames.frames:
            try:
                self.sock.sendto(frame, self.qgc)
                self.sent += 1
            except OSError as exc:  # QGC not started yet
                log.debug("to QGC: %s", exc)

    def receive(self, timeout: float) -> bytes | None:
        readable, _, _ = select.select([self.sock], [], [], timeout)
        if not readable:
            return None
        data, _ = self.sock.recvfrom(MAX_DATAGRAM)
        self.received += 1
        return data

    def close(self) -> None:
        self.sock.close()


def forward(node: Node, qgc: tuple[str, int], stop: threading.Event) -> UdpGroundStation:
    """Run until ``stop``: Zenoh frames -> QGC, QGC's datagrams -> Zenoh."""
    station = UdpGroundStation(qgc)
    to_autopilot = node.publisher(MAVLINK_TO_AUTOPILOT)
    node.subscribe(MAVLINK_FROM_AUTOPILOT, station.send)
    log.info("MAVLink of %s <-> UDP %s:%d (point QGroundControl there)", node.ns, *qgc)
    try:
        while not stop.is_set():
            data = station.receive(0.1)
            if data:
                to_autopilot.put(MavlinkFrames(header=Header.now(), frames=[data]))
    finally:
        station.close()
    return station


def parse_udp(text: str) -> tuple[str, int]:
    """``HOST:PORT`` -> (HOST, PORT); ValueError naming the expected form."""
    host, _, port = text.rpartition(":")
    if not host or not port.isdigit() or not 0 < int(port) < 65536:
        raise ValueError(f"--udp must be HOST:PORT (e.g. 127.0.0.1:14550), got {text!r}")
    return host, int(port)
