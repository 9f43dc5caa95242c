"""The bridge's MAVLink link with a signing key, against a vehicle on a real UDP socket: what
it sends is signed with the key, and it drops unsigned, wrongly signed and replayed frames (a
forged frame with a future timestamp does not block the genuine stream either); RADIO_STATUS
may stay unsigned."""

from __future__ import annotations

import socket
import time

import pytest
from mavlink_signer import encoder
from pymavlink.dialects.v20 import common as mavlink

from dronewrapper.security.keystore import KeyStore
from dronewrapper_bridge_mavlink.link import MavLink
from dronewrapper_bridge_mavlink.outgoing import Heartbeat
from dronewrapper_sim.mavlink_io import signing_timestamp
from support import free_port, loopback_udp


def _heartbeat(mav: mavlink.MAVLink, custom_mode: int) -> bytes:
    msg = mavlink.MAVLink_heartbeat_message(2, 12, 1, custom_mode, 4, 3)
    data = msg.pack(mav)
    mav.seq = (mav.seq + 1) % 256
    return data


@pytest.fixture
def keyed_link(tmp_path):
    store = KeyStore(tmp_path)
    key = store.new_mavlink_key()
    port = free_port(socket.SOCK_DGRAM)
    link = MavLink(f"udpin:127.0.0.1:{port}", signing_key_file=str(store.mavlink_key))
    link.open()
    vehicle = loopback_udp(2.0)
    yield link, key, vehicle, ("127.0.0.1", port)
    vehicle.close()
    link.close()


def _received(link: MavLink, wanted: int, seconds: float = 1.5) -> list:
    got, end = [], time.monotonic() + seconds
    while time.monotonic() < end and len(got) < wanted:
        msg = link.recv(0.1)
        if msg is not None and msg.get_type() != "BAD_DATA":
            got.append(msg)
    return got


def test_keyed_link_signs_and_rejects(keyed_link):
    link, key, vehicle, bridge = keyed_link
    genuine = encoder(key)
    vehicle.sendto(_heartbeat(genuine, 1), bridge)
    assert [m.custom_mode for m in _received(link, 1)] == [1]
    # what the bridge sends back is signed with the key
    link.send(Heartbeat(6, 8, 0, 0, 4))
    data, _ = vehicle.recvfrom(65535)
    checker = encoder(key)
    checker.signing.timestamp = 0
    (reply,) = checker.parse_buffer(data)
    assert reply.get_type() == "HEARTBEAT" and reply.get_signed()

    rejected_before = link.rejected
    vehicle.sendto(_heartbeat(encoder(None), 2), bridge)  # unsigned
    vehicle.sendto(_heartbeat(encoder(bytes(32)), 3), bridge)  # wrong key
    replay = _heartbeat(genuine, 4)
    vehicle.sendto(replay, bridge)
    vehicle.sendto(replay, bridge)  # the same frame again: an old timestamp
    future = encoder(bytes(32), signing_timestamp(time.time() + 3600))
    vehicle.sendto(_heartbeat(future, 5), bridge)  # forged, from the future
    vehicle.sendto(_heartbeat(genuine, 6), bridge)  # the genuine stream goes on
    radio = mavlink.MAVLink_radio_status_message(200, 190, 90, 10, 20, 0, 0).pack(encoder(None))
    vehicle.sendto(radio, bridge)
    got = _received(link, 3)
    assert [(m.get_type(), getattr(m, "custom_mode", None)) for m in got] == [
        ("HEARTBEAT", 4),
        ("HEARTBEAT", 6),
        ("RADIO_STATUS", None),
    ]
    assert link.rejected - rejected_before == 4
