"""zenoh-ros2-sdk, the tests' independent ROS 2 peer, opened on one router for a block.

Its Zenoh session and its message registry are process-wide singletons, and the registry
outlives the session it loaded types into: a second session after a closed one would find every
type "loaded" and none in its own store. :func:`ros2_peer` starts both afresh, loading the
upstream interface definitions (``tests/data/ros2_interfaces``), and closes the session at the
end, so test files may open the peer one after another in one process.
"""

from __future__ import annotations

import contextlib
from collections.abc import Iterator
from pathlib import Path

UPSTREAM = Path(__file__).resolve().parent / "data" / "ros2_interfaces"
"""The upstream .msg/.srv definitions the peer reads (its own, not the project's)."""


@contextlib.contextmanager
def ros2_peer(host: str, port: int) -> Iterator[None]:
    """The peer's session on ``host:port`` with a fresh registry while the block runs."""
    from zenoh_ros2_sdk import ZenohSession, message_registry

    if ZenohSession._instance is not None:
        ZenohSession._instance.close()
    message_registry._registry = None
    message_registry.get_registry(str(UPSTREAM))
    ZenohSession.get_instance(host, port)
    try:
        yield
    finally:
        if ZenohSession._instance is not None:
            ZenohSession._instance.close()
