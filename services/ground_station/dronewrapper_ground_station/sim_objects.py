"""The simulator's world objects as the station shows them: true poses, teleop, world loads.

Keys are registry topics (``sim/...``, no vehicle namespace); on a real aircraft no simulator
answers and the world calls raise ServiceUnavailable.
"""

from __future__ import annotations

from typing import Any

from dronewrapper.msgs import registry
from dronewrapper.msgs.geometry import Twist, Vector3
from dronewrapper.msgs.simulation import WorldLoad, WorldQuery, WorldState
from dronewrapper.runtime.contract import NodeApi
from dronewrapper_ground_station import snapshot
from dronewrapper_ground_station.undeclare import undeclare


class SimObjects:
    """The simulator's world objects: their true poses, and keyboard teleop of them."""

    WORLD_NS = registry.DEFAULT_NAMESPACE
    """The world's keys (``sim/...``) belong to no vehicle; the namespace is not used."""

    def __init__(self, node: NodeApi) -> None:
        self.node = node
        self.clock = node.clock
        self._poses: dict[str, tuple[dict[str, Any], float]] = {}
        self._publishers: dict[str, Any] = {}
        topic = registry.SIM_OBJECT_POSE
        self._subs = [node.subscribe(topic, self._on_pose, key=topic.wildcard(), keyed=True)]

    def _on_pose(self, key: str, msg: Any) -> None:
        parts = registry.SIM_OBJECT_POSE.match(key)
        if parts is not None:
            self._poses[parts["name"]] = (snapshot.pose_fields(msg), self.clock())

    def snapshot(self) -> dict[str, Any]:
        """``{name: {x, y, z, yaw, age}}`` of the objects seen in the last 5 s."""
        now = self.clock()
        return {
            name: {**fields, "age": round(now - at, 3)}
            for name, (fields, at) in sorted(self._poses.items())
            if now - at < 5.0
        }

    def move(self, name: str, east: float, north: float) -> None:
        """Send one velocity command (ENU m/s) to object ``name``; the sim lets it expire."""
        if name not in self._poses:
            raise KeyError(f"no simulated object {name!r}")
        pub = self._publishers.get(name)
        if pub is None:
            topic = registry.SIM_OBJECT_CMD_VEL
            pub = self._publishers[name] = self.node.publisher(topic, key=topic.key(name=name))
        pub.put(Twist(linear=Vector3(x=east, y=north, z=0.0)))

    def world(self, timeout: float = 3.0) -> WorldState:
        """The simulator's world (scenario, objects, loadable scenarios).

        Raises:
            ServiceUnavailable: no simulator answers (a real aircraft, or none running).
        """
        return self.node.call(registry.SIM_WORLD, WorldQuery(), ns=self.WORLD_NS, timeout=timeout)

    def load(self, scenario: str, timeout: float = 10.0) -> WorldState:
        """Load scenario ``scenario``'s world (the running one again: reset its objects).

        Raises:
            ServiceError: the simulator refused (an unknown scenario: ``bad_request``).
            ServiceUnavailable: no simulator answers.
        """
        request = WorldLoad(scenario=scenario)
        return self.node.call(registry.SIM_WORLD_LOAD, request, ns=self.WORLD_NS, timeout=timeout)

    def close(self) -> None:
        undeclare([*self._subs, *self._publishers.values()])
