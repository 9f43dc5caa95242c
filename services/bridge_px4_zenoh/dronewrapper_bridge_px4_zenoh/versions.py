"""Which versions of its messages a firmware speaks, learned from what it announces.

px4_msgs change between firmware versions, and a type's RIHS01 hash changes with its fields. PX4
names the hash in every data key and in the liveliness token of each of its publishers and
subscribers (``MP``/``MS``). :class:`Versions` compares what the firmware announces with the
hashes of the bridge's own definitions (:mod:`.px4_msgs`): a topic whose hash matches is
decoded (and, for ``/fmu/in``, written on the firmware's exact key); one that differs is
refused with a :class:`VersionMismatch` that names the topic, the type, and both hashes.
"""

from __future__ import annotations

from dataclasses import dataclass

from dronewrapper_bridge_px4_zenoh.topics import BY_NAME, Px4Topic
from dronewrapper_ros2_codec.interfaces import dds_type_name
from dronewrapper_ros2_codec.names import PUBLISHER, SUBSCRIBER, Endpoint
from dronewrapper_ros2_codec.typehash import type_hash

FIRMWARE = "PX4 main of 2026-03-02 (02e73e3b6f)"
"""The firmware whose messages the bridge's definitions are (its hashes match them)."""


@dataclass(frozen=True)
class VersionMismatch:
    """A topic the firmware announces with another type or version than the bridge knows
    (types as DDS names, ``px4_msgs::msg::dds_::VehicleStatus_``)."""

    topic: str
    expected_type: str
    expected_hash: str
    seen_type: str
    seen_hash: str

    def __str__(self) -> str:
        seen = f"{self.seen_type} with hash {self.seen_hash}"
        expected = f"hash {self.expected_hash}"
        if self.seen_type != self.expected_type:
            expected = f"{self.expected_type} with {expected}"
        return (
            f"PX4's {self.topic} is {seen}, but this bridge knows {expected} ({FIRMWARE}): "
            "the firmware's message differs, so the bridge leaves the topic alone; run a bridge "
            "whose px4_msgs match this firmware, or the firmware it knows"
        )


class Versions:
    """The hashes the firmware announced, per topic, checked against the bridge's own."""

    def __init__(self, domain: int = 0) -> None:
        self.domain = domain
        self.expected: dict[str, str] = {
            name: type_hash(topic.type_name) for name, topic in BY_NAME.items()
        }
        self.agreed: set[str] = set()
        self.mismatches: dict[str, VersionMismatch] = {}

    def learn(self, endpoint: Endpoint) -> VersionMismatch | None:
        """Take one of PX4's publisher or subscriber tokens: None if it is of no topic the
        bridge uses or its type and hash agree, else the mismatch (kept in :attr:`mismatches`)."""
        if endpoint.kind not in (PUBLISHER, SUBSCRIBER) or endpoint.domain != self.domain:
            return None
        return self.check(endpoint.topic, endpoint.type_name, endpoint.type_hash)

    def check(self, topic_name: str, type_name: str, seen_hash: str) -> VersionMismatch | None:
        """Compare one topic's announced DDS type name and hash with the bridge's."""
        topic = BY_NAME.get(topic_name)
        if topic is None:
            return None
        expected = self.expected[topic_name]
        wanted_type = dds_type_name(topic.type_name)
        if type_name == wanted_type and seen_hash == expected:
            self.agreed.add(topic_name)
            self.mismatches.pop(topic_name, None)
            return None
        mismatch = VersionMismatch(topic_name, wanted_type, expected, type_name, seen_hash)
        self.agreed.discard(topic_name)
        self.mismatches[topic_name] = mismatch
        return mismatch

    def usable(self, topic: Px4Topic) -> bool:
        """True once the firmware announced the topic with the bridge's version of its type."""
        return topic.name in self.agreed

    def key(self, topic: Px4Topic) -> str:
        """The exact data key of ``topic`` in the bridge's version (PX4 subscribes on it)."""
        return topic.key(self.domain, self.expected[topic.name])
