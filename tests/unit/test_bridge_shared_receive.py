"""A MAVLink bridge's UDP link on a host's shared loop (node.SharedReceive): the real bridge
and link on the fake bus, the link's socket bound on loopback and nothing sent; a link error
closes the link, and the loop reopens it a second later."""

from __future__ import annotations

import math

from dronewrapper.runtime.fake import FakeBus, FakeNode
from dronewrapper.runtime.poller import NO_FILE
from dronewrapper_bridge_mavlink.config import Config
from dronewrapper_bridge_mavlink.node import PORTS, Bridge, SharedReceive
from dronewrapper_compose.ports import free_port


def test_a_link_error_closes_the_link_and_the_loop_reopens_it_a_second_later():
    bus = FakeBus(start=1000.0)
    node = FakeNode("bridge_mavlink", bus, ports=PORTS)
    config = Config(connection=f"udpin:127.0.0.1:{free_port('udp')}")
    bridge = Bridge(node, config)
    reader = SharedReceive(bridge)
    try:
        assert reader.fileno() == NO_FILE  # not open yet
        assert reader.on_due(1000.0) == math.inf  # opened
        assert bridge.link.is_udp and reader.fileno() >= 0
        assert reader.on_readable() is None  # nothing waits: an empty batch, no error

        bridge.link._conn.port.close()  # the socket fails under the link
        again = reader.on_readable()
        assert again == node.clock.monotonic() + SharedReceive.REOPEN_S
        assert not bridge.link.is_open and reader.fileno() == NO_FILE

        assert reader.on_due(again) == math.inf  # reopened
        assert bridge.link.is_open and reader.fileno() >= 0
        assert bridge.reconnects.count >= 1
    finally:
        bridge.link.close()
        node.stop()
