"""bridge_tello's Bridge started in this process against a ScriptedTello over real UDP.

:func:`running_bridge` gives the Tello (on a random loopback address of its own), the started
Bridge and a user node, on the fake bus or on a real Zenoh router, and stops all of them after.
The Tello answers in real time, so the bridge's node runs on the real clock on either bus.
"""

from __future__ import annotations

import random
from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any

from tello_peer import ScriptedTello

from dronewrapper.runtime.clock import REAL
from dronewrapper.runtime.config import load_config
from dronewrapper.runtime.fake import FakeBus, FakeNode
from dronewrapper_bridge_tello.config import Config
from dronewrapper_bridge_tello.node import PORTS, Bridge
from support import client_node, wait_for


@contextmanager
def running_bridge(
    extra: list[str], router: str = "", *, mode: str = "client"
) -> Iterator[tuple[ScriptedTello, Bridge, Any]]:
    """A scripted Tello on a random loopback address and a started Bridge talking to it (video
    off, ``extra`` as more ``--set`` values), with a user node: on the fake bus, or on a real
    Zenoh router as Zenoh ``mode`` sessions when ``router`` is given."""
    address = f"127.{random.randint(10, 250)}.{random.randint(0, 255)}.{random.randint(2, 250)}"
    tello = ScriptedTello(address)
    tello.start()
    config = load_config(
        Config,
        None,
        [f"tello_address={address}", f"local_address={address}", "video=false", *extra],
    )
    if router:
        node = client_node(router, name="bridge_tello", mode=mode)
        user = client_node(router, name="test", mode=mode)
    else:
        bus = FakeBus()
        node, user = FakeNode("bridge_tello", bus, ports=PORTS), FakeNode("test", bus)
        node.clock = REAL  # the bridge's time is its node's: real, as the Tello answers in it
    bridge = Bridge(node, config)
    threads = bridge.start()
    try:
        wait_for(
            lambda: bridge.core.connected and bridge.core.sdk_mode, 10, what="bridge connected"
        )
        yield tello, bridge, user
    finally:
        node.stop()
        for thread in threads:
            thread.join(2)
        bridge.link.close()
        user.close()
        node.close()
        tello.stop.set()
        tello.join(2)
        tello.sock.close()
