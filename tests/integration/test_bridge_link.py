"""The bridge's MAVLink link over each URL kind pymavlink takes (real loopback sockets)."""

from __future__ import annotations

import socket
import time

import pytest

from dronewrapper_bridge_mavlink.link import MavLink
from dronewrapper_bridge_mavlink.outgoing import Heartbeat
from support import free_port


def exchange(a: MavLink, b: MavLink, timeout: float = 5.0) -> tuple[object, object]:
    """a and b send heartbeats until each has received one from the other."""
    got: dict[str, object] = {}
    deadline = time.monotonic() + timeout
    while len(got) < 2 and time.monotonic() < deadline:
        a.send(Heartbeat(6, 8, 0, 0, 4))
        b.send(Heartbeat(2, 12, 29, 0, 3))
        for name, link in (("a", a), ("b", b)):
            msg = link.recv(0.05)
            if msg is not None and msg.get_type() == "HEARTBEAT":
                got.setdefault(name, msg)
    assert len(got) == 2, f"only {sorted(got)} received"
    return got["a"], got["b"]


@pytest.mark.parametrize(
    ("server", "client"),
    [("udpin:127.0.0.1:{port}", "udpout:127.0.0.1:{port}"),
     ("tcpin:127.0.0.1:{port}", "tcp:127.0.0.1:{port}")],
)  # fmt: skip
def test_url_kinds_talk_both_ways(server, client):
    kind = socket.SOCK_DGRAM if server.startswith("udp") else socket.SOCK_STREAM
    port = free_port(kind)
    a = MavLink(server.format(port=port), source_system=255, source_component=190)
    b = MavLink(client.format(port=port), source_system=1, source_component=1)
    a.open()
    b.open()
    try:
        if server.startswith("udp"):  # a udpin link answers whoever spoke first
            b.send(Heartbeat(2, 12, 29, 0, 3))
        from_b, from_a = exchange(a, b)
        assert from_b.get_srcSystem() == 1 and from_b.autopilot == 12
        assert from_a.get_srcSystem() == 255 and from_a.type == 6
    finally:
        a.close()
        b.close()


def test_bad_url_raises_and_closed_link_is_quiet():
    link = MavLink("udpin:not-a-host:notaport")
    with pytest.raises((OSError, ValueError)):
        link.open()
    assert not link.is_open
    assert link.send(Heartbeat(6, 8, 0, 0, 4)) is False
    assert link.recv(0.01) is None


def test_serial_device_with_baud_over_a_pty():
    """A serial URL (device path + baud) on a pseudo-terminal, the autopilot on the other end."""
    import os
    import select
    import tty

    from pymavlink.dialects.v20 import common as mavlink2

    master, slave = os.openpty()
    tty.setraw(master)
    link = MavLink(os.ttyname(slave), baud=921600, source_system=255, source_component=190)
    link.open()
    autopilot = mavlink2.MAVLink(None, srcSystem=1, srcComponent=1)
    try:
        os.write(master, autopilot.heartbeat_encode(2, 12, 29, 0, 3).pack(autopilot))
        msg = None
        deadline = time.monotonic() + 5
        while msg is None and time.monotonic() < deadline:
            msg = link.recv(0.1)
        assert msg is not None and msg.get_type() == "HEARTBEAT" and msg.autopilot == 12
        assert link.send(Heartbeat(6, 8, 0, 0, 4))
        parser = mavlink2.MAVLink(None)
        got = None
        while got is None and time.monotonic() < deadline:
            readable, _, _ = select.select([master], [], [], 0.1)  # bounded wait
            if readable:
                got = parser.parse_char(os.read(master, 280))
        assert got is not None and got.get_type() == "HEARTBEAT" and got.type == 6
    finally:
        link.close()
        os.close(master)
        os.close(slave)


def test_udp_link_reads_every_frame_of_a_datagram_and_times_out_when_silent():
    from pymavlink.dialects.v20 import common as mavlink

    port = free_port(socket.SOCK_DGRAM)
    link = MavLink(f"udpin:127.0.0.1:{port}")
    link.open()
    sender = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    try:
        packer = mavlink.MAVLink(None, srcSystem=1, srcComponent=1)
        frames = [
            mavlink.MAVLink_heartbeat_message(2, 12, 0, 0, 3, 3).pack(packer),
            mavlink.MAVLink_local_position_ned_message(10, 1.0, 2.0, -3.0, 0, 0, 0).pack(packer),
        ]
        sender.sendto(b"".join(frames), ("127.0.0.1", port))  # PX4 packs frames like this
        kinds = [getattr(link.recv(2.0), "get_type", lambda: None)() for _ in frames]
        assert kinds == ["HEARTBEAT", "LOCAL_POSITION_NED"]
        assert link.last_source == ("127.0.0.1", sender.getsockname()[1])
        start = time.monotonic()
        assert link.recv(0.1) is None
        assert 0.09 <= time.monotonic() - start < 1.0  # waited its timeout, not more
    finally:
        sender.close()
        link.close()
