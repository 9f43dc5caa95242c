"""A recording stand-in for the ROS 2 side's Zenoh session (what the gateway declares on it:
keys, callbacks, liveliness tokens), for the gateway's tests on the fake bus."""

from __future__ import annotations

from types import SimpleNamespace
from typing import Any

from dronewrapper_ros2_codec.names import topic_key
from dronewrapper_ros2_codec.typehash import type_hash

ZID = "c0ffee00c0ffee00c0ffee00c0ffee00"
PT = "mavros_msgs/msg/PositionTarget"


class RosPublisher:
    def __init__(self, key: str) -> None:
        self.key = key
        self.sent: list[tuple[bytes, bytes]] = []
        self.matching_status = SimpleNamespace(matching=False)

    def put(self, payload: bytes, *, attachment: bytes) -> None:
        self.sent.append((payload, attachment))

    def undeclare(self) -> None:
        pass


class RosSession:
    """Records what the gateway declares on the ROS 2 side (keys, callbacks, tokens)."""

    def __init__(self) -> None:
        self.publishers: dict[str, RosPublisher] = {}
        self.subscribers: dict[str, Any] = {}
        self.queryables: dict[str, Any] = {}
        self.tokens: list[str] = []
        self.watchers: dict[str, Any] = {}

    def zid(self) -> str:
        return ZID

    def declare_publisher(self, key: str, **_qos: Any) -> RosPublisher:
        self.publishers[key] = RosPublisher(key)
        return self.publishers[key]

    def declare_subscriber(self, key: str, callback: Any, **_kw: Any) -> Any:
        target = self.watchers if key.startswith("@ros2_lv") else self.subscribers
        target[key] = callback
        return SimpleNamespace(undeclare=lambda: None)

    def declare_queryable(self, key: str, callback: Any, *, complete: bool) -> Any:
        assert complete  # rmw_zenoh's services are complete queryables
        self.queryables[key] = callback
        return SimpleNamespace(undeclare=lambda: None)

    def liveliness(self) -> RosSession:
        return self

    def declare_token(self, key: str) -> Any:
        self.tokens.append(key)
        return SimpleNamespace(undeclare=lambda: None)


def ros_key(name: str, ros_type: str) -> str:
    return topic_key(0, name, ros_type, type_hash(ros_type))
