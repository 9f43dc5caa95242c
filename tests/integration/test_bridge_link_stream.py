"""The bridge's link on a byte stream (TCP): frames split across reads arrive whole, and a
link whose peer closed the connection reconnects and reads from the new one.

A plain TCP server on loopback stands in for the autopilot (SITL's ``tcpin``), writing real
pymavlink frames.
"""

from __future__ import annotations

import socket
import time

import pytest
from pymavlink.dialects.v20 import common as mavlink

from dronewrapper_bridge_mavlink.link import MavLink

pytestmark = pytest.mark.integration


def heartbeat(mav: mavlink.MAVLink) -> bytes:
    return bytes(mavlink.MAVLink_heartbeat_message(2, 12, 0x81, 0, 4, 3).pack(mav))


def receive(link: MavLink, kind: str, timeout: float) -> object:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        msg = link.recv(0.1)
        if msg is not None and msg.get_type() == kind:
            return msg
    raise AssertionError(f"no {kind} within {timeout} s")


def test_a_frame_split_across_writes_arrives_and_a_closed_link_reconnects():
    mav = mavlink.MAVLink(None, srcSystem=1, srcComponent=1)
    with socket.create_server(("127.0.0.1", 0)) as server:
        port = server.getsockname()[1]
        link = MavLink(f"tcp:127.0.0.1:{port}")
        link.open()
        try:
            first, _ = server.accept()
            frame = heartbeat(mav)
            first.sendall(frame[:5])  # the frame's start ...
            assert link.recv(0.3) is None  # ... is held until the rest comes
            first.sendall(frame[5:] + heartbeat(mav)[:3])
            assert receive(link, "HEARTBEAT", 5).get_srcSystem() == 1
            first.close()  # the autopilot restarts: the link reconnects by itself

            server.settimeout(10)
            link.recv(0.5)  # reads the end of the stream, reconnects
            second, _ = server.accept()
            with second:
                second.sendall(heartbeat(mav))
                assert receive(link, "HEARTBEAT", 5) is not None
        finally:
            link.close()
