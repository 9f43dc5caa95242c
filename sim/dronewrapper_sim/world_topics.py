"""The simulated world on Zenoh, the same for every simulated aircraft: ground truth, object
poses and teleop, and the world control services (which scenario runs; load or reset it)."""

from __future__ import annotations

import logging
import threading
from collections.abc import Callable
from typing import Any

import numpy as np

from dronewrapper.msgs import registry
from dronewrapper.msgs.geometry import Twist
from dronewrapper.msgs.simulation import VehicleResetResult, WorldLoad, WorldState
from dronewrapper.rotations import quat_from_rpy
from dronewrapper.runtime import ServiceError
from dronewrapper.runtime.contract import NodeApi
from dronewrapper_sim.pose_snapshot import PoseSnapshot, pose_msg
from dronewrapper_sim.world.scenario import SCENARIO_NAMES, load_scenario

log = logging.getLogger("sim")


class WorldTopics:
    """The world on Zenoh, the same for every aircraft: the vehicle's ``{ns}/sim/ground_truth``
    (while someone subscribes), ``sim/objects/{name}/pose`` of each object, and their teleop
    ``sim/objects/{name}/cmd_vel``.

    Args:
        node: the Zenoh node.
        world: the world whose objects are published and teleoperated.
        world_lock: the lock the simulation holds while it steps ``world``.
        reset_vehicle: puts the vehicle back at its start pose, on the ground, motors off,
            and says what it did; served as ``{ns}/sim/world/reset`` when given.
    """

    def __init__(
        self,
        node: NodeApi,
        world: Any,
        world_lock: threading.Lock,
        *,
        seed: int | None = None,
        reset_vehicle: Callable[[], str] | None = None,
    ) -> None:
        self.node = node
        self.world = world
        self.world_lock = world_lock
        self.seed = seed
        self.cmd_vel_errors = 0
        self.loads = 0
        self._gt_pub = node.publisher(registry.SIM_GROUND_TRUTH)
        self._gt_watched = False
        self._gt_listener = self._gt_pub.on_matching(self._on_gt_matching)
        self._gt_watched = self._gt_watched or self._gt_pub.watched()
        self._object_pubs: dict[str, Any] = {}
        self._declare_objects()
        node.serve(registry.SIM_WORLD, lambda _request: self.state())
        node.serve(registry.SIM_WORLD_LOAD, self.load)
        if reset_vehicle is not None:
            node.serve(registry.SIM_RESET, lambda _request: self._reset(reset_vehicle))

    def _reset(self, reset_vehicle: Callable[[], str]) -> VehicleResetResult:
        message = reset_vehicle()
        log.info("vehicle reset: %s", message)
        return VehicleResetResult(success=True, message=message)

    def _declare_objects(self) -> None:
        """Pose publishers and teleop subscribers of the objects not declared yet."""
        for obj in self.world.objects:
            if obj.name in self._object_pubs:
                continue
            self._object_pubs[obj.name] = self.node.publisher(
                registry.SIM_OBJECT_POSE, name=obj.name
            )
            self.node.subscribe(
                registry.SIM_OBJECT_CMD_VEL, self._teleop_callback(obj.name), name=obj.name
            )

    def state(self) -> WorldState:
        """The running world: its scenario, objects, and the scenarios it can load."""
        return WorldState(
            scenario=self.world.scenario.name,
            objects=[obj.name for obj in self.world.objects],
            available=list(SCENARIO_NAMES),
            loads=self.loads,
        )

    def load(self, request: WorldLoad) -> WorldState:
        """Load a fixed scenario's world (its objects from their start; the same name resets
        it). The aircraft stays where it is. Only fixed names are accepted: a remote caller
        never makes the simulator read a file of its choosing."""
        if request.scenario not in SCENARIO_NAMES:
            raise ServiceError(
                f"unknown scenario {request.scenario!r}; known: {', '.join(SCENARIO_NAMES)}",
                "bad_request",
            )
        scenario = load_scenario(request.scenario)
        with self.world_lock:
            self.world.load(scenario, self.seed)
            self.loads += 1
        self._declare_objects()
        log.info("world loaded: scenario %s, %d objects", scenario.name, len(self.world.objects))
        return self.state()

    def _on_gt_matching(self, matching: bool) -> None:
        self._gt_watched = matching

    def publish_ground_truth(self, snapshot: PoseSnapshot) -> None:
        """Publish the vehicle's true pose while someone subscribes to it (a fleet's sims, that
        nobody watches, spend nothing on it)."""
        if self._gt_watched:
            self._gt_pub.put(pose_msg(snapshot, seq=self._gt_pub.count))

    def publish_objects(self) -> None:
        """Publish the true pose of every world object (stamped now)."""
        stamp = self.node.clock.time()
        for obj in self.world.objects:
            pub = self._object_pubs.get(obj.name)
            if pub is None:
                continue
            x, y, z = (float(v) for v in obj.position)
            snap = PoseSnapshot((x, y, z), quat_from_rpy(0.0, 0.0, float(obj.yaw)), stamp)
            pub.put(pose_msg(snap, seq=pub.count))

    def _teleop_callback(self, name: str) -> Callable[[Twist], None]:
        def on_cmd_vel(msg: Twist) -> None:
            lin = np.array([msg.linear.x, msg.linear.y, msg.linear.z], dtype=float)
            try:
                with self.world_lock:
                    self.world.set_cmd_vel(name, lin, float(msg.angular.z), self.world.time_s)
            except (KeyError, ValueError) as exc:
                self.cmd_vel_errors += 1
                log.warning("cmd_vel for %s refused: %s", name, exc)

        return on_cmd_vel
