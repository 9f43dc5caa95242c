"""Type disagreements on a ROS 2 graph, read from rmw_zenoh liveliness tokens.

rmw_zenoh subscribes on the exact key ``<domain>/<topic>/<type>/<hash>``: a publisher and a
subscriber whose builds of a message hash differently never meet, and neither side says so.
Every endpoint announces its type and hash in its token, so whoever reads the tokens can: two
endpoints on one topic (same domain) with different types or hashes disagree. A Humble peer
announces ``TypeHashNotSupported`` and never meets a Jazzy or later one.
"""

from __future__ import annotations

from collections import defaultdict
from collections.abc import Iterable
from dataclasses import dataclass

from dronewrapper_ros2_codec.names import (
    CLIENT,
    PUBLISHER,
    SERVICE,
    SUBSCRIBER,
    Endpoint,
)
from dronewrapper_ros2_codec.typehash import HUMBLE

ROLE = {PUBLISHER: "publishes", SUBSCRIBER: "subscribes", SERVICE: "serves", CLIENT: "calls"}


@dataclass(frozen=True)
class Disagreement:
    """One topic or service whose endpoints do not agree on its type: each variant
    ``(type, hash)`` with the endpoints (node, kind, zid) that use it."""

    domain: int
    topic: str
    variants: dict[tuple[str, str], list[Endpoint]]

    def involves(self, zid: str) -> bool:
        """True if an endpoint of Zenoh session ``zid`` is part of it."""
        return any(e.zid == zid for group in self.variants.values() for e in group)

    def describe(self) -> str:
        """One sentence naming the topic, each side and its hash."""
        sides = []
        for (type_name, type_hash), endpoints in sorted(self.variants.items()):
            who = ", ".join(sorted({f"{e.node} {ROLE[e.kind]}" for e in endpoints}))
            distro = " (ROS 2 Humble: no type hashes)" if type_hash == HUMBLE else ""
            sides.append(f"{who} it as {type_name} {type_hash}{distro}")
        return (
            f"ROS 2 type mismatch on {self.topic} (domain {self.domain}): "
            + "; ".join(sides)
            + ": these endpoints never exchange a message"
        )


def disagreements(endpoints: Iterable[Endpoint]) -> list[Disagreement]:
    """Every topic or service name (per domain) used with more than one type or hash (pure)."""
    by_topic: dict[tuple[int, str], dict[tuple[str, str], list[Endpoint]]] = defaultdict(
        lambda: defaultdict(list)
    )
    for e in endpoints:
        by_topic[(e.domain, e.topic)][(e.type_name, e.type_hash)].append(e)
    return [
        Disagreement(domain, topic, dict(variants))
        for (domain, topic), variants in sorted(by_topic.items())
        if len(variants) > 1
    ]
