"""The station subscribes each telemetry key once per drone: its drone client's input holders
are the ones it shows, not a second set beside them (counted on the fake bus)."""

from __future__ import annotations

import collections
from typing import Any

import pytest

from dronewrapper.msgs import registry
from dronewrapper.runtime.fake import FakeBus, FakeNode
from dronewrapper_ground_station.config import Config
from dronewrapper_ground_station.fleet import TELEMETRY, Fleet

pytestmark = pytest.mark.timeout(60)
DRONES = ("drone1", "drone2")


class CountingNode(FakeNode):
    """A fake node that counts its subscriptions per key and keeps them (active or not)."""

    def __init__(self, name: str, bus: FakeBus) -> None:
        super().__init__(name, bus)
        self.declared: list[tuple[str, Any]] = []

    def subscribe(self, topic: Any, callback: Any, *, key: str | None = None, **kw: Any) -> Any:
        parts = {k: v for k, v in kw.items() if k not in ("keyed", "direct")}
        sub = super().subscribe(topic, callback, key=key, **kw)
        self.declared.append((key or topic.key(self.ns, **parts), sub))
        return sub

    def active(self) -> collections.Counter[str]:
        return collections.Counter(key for key, sub in self.declared if sub.active)


def test_each_telemetry_key_is_subscribed_once_per_drone():
    bus = FakeBus()
    node = CountingNode("station", bus)
    fleet = Fleet(node, Config(port=0, namespaces=list(DRONES)))
    try:
        counts = node.active()
        topics = [topic for _, topic, _ in TELEMETRY] + [registry.STATUSTEXT, registry.REFUSAL]
        for ns in DRONES:
            per_key = {topic.key(ns): counts[topic.key(ns)] for topic in topics}
            assert per_key == dict.fromkeys(per_key, 1), ns
        doubled = {key: n for key, n in counts.items() if n > 1}
        assert doubled == {}
    finally:
        fleet.close()
    assert node.active() == {}  # closing the station leaves no subscription behind
