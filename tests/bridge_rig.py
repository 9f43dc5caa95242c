"""The bridge in-process on a real router, facing an AutopilotPeer over UDP loopback."""

from __future__ import annotations

import contextlib
import threading
import time
from collections.abc import Iterator
from dataclasses import dataclass, field

from autopilot_peer import AutopilotPeer

from dronewrapper.msgs import registry
from dronewrapper.msgs.mavros import ParamGet
from dronewrapper.runtime import Node, ServiceError, ServiceUnavailable
from dronewrapper_bridge_mavlink.config import Config
from dronewrapper_bridge_mavlink.node import Bridge
from support import client_node, free_port, wait_for


@dataclass
class Collected:
    """Messages a test subscribed to, with their receive times (monotonic s)."""

    items: list[tuple[float, object]] = field(default_factory=list)
    lock: threading.Lock = field(default_factory=threading.Lock)

    def __call__(self, msg: object) -> None:
        with self.lock:
            self.items.append((time.monotonic(), msg))

    def values(self, since: float = 0.0) -> list:
        with self.lock:
            return [m for at, m in self.items if at >= since]


@dataclass
class Rig:
    bridge: Bridge
    peer: AutopilotPeer
    user: Node
    poses: Collected
    texts: Collected

    def text_containing(self, fragment: str) -> str | None:
        for text in self.texts.values():
            if fragment in text.text:
                return text.text
        return None


def reaches_bridge(user: Node) -> bool:
    """True once the user's calls reach the bridge (an invalid param_id gets an error reply)."""
    try:
        user.call(registry.PARAM_GET, ParamGet(param_id="X" * 17), timeout=5)
    except ServiceUnavailable:
        return False
    except ServiceError:
        return True
    return True


@contextlib.contextmanager
def bridge_rig(router: str, *, telemetry: bool = True, **config) -> Iterator[Rig]:
    """A started bridge (``config`` overrides), a connected peer, and a user node."""
    import socket

    port = free_port(socket.SOCK_DGRAM)
    cfg = Config(connection=f"udpin:127.0.0.1:{port}", **config)
    node = client_node(router, name="bridge_mavlink")
    bridge = Bridge(node, cfg)
    threads = bridge.start()
    peer = AutopilotPeer(port, telemetry=telemetry)
    user = client_node(router, name="user")
    poses, texts = Collected(), Collected()
    try:
        user.subscribe(registry.LOCAL_POSE, poses)
        user.subscribe(registry.STATUSTEXT, texts)
        wait_for(lambda: bridge.core.connected, 20, what="the bridge to hear the peer")
        wait_for(lambda: reaches_bridge(user), 20, what="the user's calls to reach the bridge")
        yield Rig(bridge, peer, user, poses, texts)
    finally:
        user.close()
        node.stop()
        for thread in threads:
            thread.join(3)
        bridge.link.close()
        node.close()
        peer.close()
