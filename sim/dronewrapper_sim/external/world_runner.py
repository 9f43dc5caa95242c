"""The world around an external autopilot, run in real time: no autopilot or physics of ours.

The main loop waits on the truth link (``select``), turns each truth sample into the scenario's
frame (:mod:`alignment`, the first sample fixes the alignment) and the wall clock
(:mod:`pose_buffer`), publishes it as ``{ns}/sim/ground_truth`` (stamped with its wall-clock
time), steps the world by wall time, publishes ``sim/objects/{name}/pose`` and, each second,
``{ns}/sim/pose_source``. The camera thread renders from the pose at each frame's capture time
(interpolated or extrapolated, see :mod:`pose_buffer`), and the frame's ``header.stamp`` is that
time. Before the first truth the vehicle stands at the scenario's start.

The scenario's clock starts when the vehicle first leaves the ground (its truth above
``TAKEN_OFF_M``): the world's objects stand at their start until then, so a firmware's boot
(PX4 about 5 s, ArduCopter's GPS fix about 40 s) and its take-off do not eat into the scenario
(a beacon drifting sideways would otherwise have left the view before the vehicle is up).
"""

from __future__ import annotations

import logging
import math
import select
import threading
from typing import Any

from dronewrapper.msgs import registry
from dronewrapper.msgs.simulation import PoseSourceStatus
from dronewrapper.rotations import quat_from_rpy
from dronewrapper.runtime import Node
from dronewrapper_sim.external.alignment import Alignment
from dronewrapper_sim.external.links import TruthLink, default_link
from dronewrapper_sim.external.pose_buffer import AgeStats, ClockMap, PoseBuffer, TimedPose
from dronewrapper_sim.external.truth import decode
from dronewrapper_sim.pose_snapshot import PoseSnapshot
from dronewrapper_sim.world.scenario import Scenario
from dronewrapper_sim.world_topics import WorldTopics

log = logging.getLogger("sim.external")

WORLD_STEP_S = 0.02  # the world's objects move in steps of about this (wall s)
MAX_WORLD_STEP_S = 0.25  # after a stall the world jumps at most this far
STATUS_PERIOD_S = 1.0
LOG_PERIOD_S = 10.0
TAKEN_OFF_M = 0.3  # above its start height: the vehicle has left the ground (m)


class ExternalPose:
    """The vehicle pose from an autopilot's truth: alignment, wall clock, buffer, frame ages.
    Pure apart from the lock: time is passed in."""

    def __init__(self, scenario: Scenario, max_extrapolation_s: float = 0.1) -> None:
        self.start = scenario.vehicle
        self.alignment: Alignment | None = None
        self.clock = ClockMap()
        self.buffer = PoseBuffer(max_extrapolation_s)
        self.ages = AgeStats()
        self.airborne = False  # the vehicle has left the ground (the scenario's clock runs)
        self._lock = threading.Lock()

    def add(self, msg: Any, arrival_s: float) -> PoseSnapshot | None:
        """Take one truth message that arrived at ``arrival_s`` (wall s); the pose it holds,
        stamped with its wall-clock time (None: not a truth, or not newer than the last)."""
        truth = decode(msg)
        if truth is None:
            return None
        with self._lock:
            if self.alignment is None:
                self.alignment = Alignment(truth, self.start.x, self.start.y, self.start.yaw)
                log.info(
                    "aligned: the autopilot's start (%.7f, %.7f, %.2f m) is the scenario's "
                    "(%.2f, %.2f), turned %.1f deg",
                    truth.lat_deg, truth.lon_deg, truth.alt_m, self.start.x, self.start.y,
                    math.degrees(self.alignment.rotation),
                )  # fmt: skip
            local = self.alignment.local(truth)
            if local.position[2] > TAKEN_OFF_M and not self.airborne:
                self.airborne = True
                log.info("the vehicle left the ground: the scenario's objects start moving")
            t = self.clock.wall_time(truth.time_s, arrival_s)
            if not self.buffer.add(TimedPose(t, local)):
                return None
        return PoseSnapshot(local.position, quat_from_rpy(*local.rpy), t)

    def frame_pose(self, now: float) -> PoseSnapshot:
        """The pose a frame captured at ``now`` is rendered from (its age is recorded)."""
        with self._lock:
            pose = self.buffer.at(now)
            if pose is None:
                return PoseSnapshot(
                    (self.start.x, self.start.y, 0.0), quat_from_rpy(0, 0, self.start.yaw), now
                )
            self.ages.add(pose)
        return PoseSnapshot(pose.position, quat_from_rpy(*pose.rpy), now)

    def status(self, source: str, link: TruthLink, now: float) -> PoseSourceStatus:
        """The status since the last call (frame ages reset)."""
        with self._lock:
            frames, mean, p95, worst, extrapolated = self.ages.report()
            newest = self.buffer.newest
            aligned = self.alignment is not None
            rotation = self.alignment.rotation if self.alignment else 0.0
        return PoseSourceStatus(
            source=source,
            link=link.spec,
            truth_rate_hz=link.measured_rate_hz(now),
            truth_age_s=now - newest.t if newest else math.nan,
            frames=frames,
            age_mean_s=mean,
            age_p95_s=p95,
            age_max_s=worst,
            extrapolated_share=extrapolated,
            aligned=aligned,
            rotation_rad=rotation,
        )


def make_cameras(config: Any, scenario: Scenario, node: Node, world: Any, pose_source: Any) -> Any:
    """The frontal and ventral cameras of ``scenario`` rendering ``world`` from ``pose_source``."""
    from pathlib import Path

    from dronewrapper_sim.camera_stream import CameraStreamer
    from dronewrapper_sim.render.camera import FRONTAL, VENTRAL, PinholeCamera
    from dronewrapper_sim.render.renderer import Renderer

    cam = scenario.camera
    camera = PinholeCamera(
        width=config.width or cam.width,
        height=config.height or cam.height,
        hfov_rad=math.radians(cam.hfov_deg),
    )
    sprites = Path(config.sprites) if config.sprites else None
    return CameraStreamer(
        node,
        Renderer(world, camera, sprites_dir=sprites),
        [FRONTAL, VENTRAL],
        config.camera_rate_hz or cam.rate_hz,
        pose_source,
        compressed=config.compressed,
        jpeg_quality=config.jpeg_quality,
        render_unwatched=config.render_unwatched,
    )


class ExternalWorldRunner:
    """The world, its topics and cameras around an external autopilot (see module doc).

    Args:
        config: the simulator's settings (``autopilot``, ``autopilot_link``, cameras ...).
        scenario: the world to simulate.
        node: the Zenoh node.
    """

    def __init__(self, config: Any, scenario: Scenario, node: Node) -> None:
        from dronewrapper_sim.world.world import World

        self.config = config
        self.scenario = scenario
        self.node = node
        self.source = config.autopilot
        seed = scenario.seed if config.seed is None else config.seed
        self.world = World(scenario, seed=seed)
        self.world_lock = threading.Lock()
        self.pose = ExternalPose(scenario, config.max_extrapolation_s)
        self.link = TruthLink(
            config.autopilot,
            config.autopilot_link or default_link(config.autopilot),
            config.truth_rate_hz,
        )
        self.world_topics = WorldTopics(node, self.world, self.world_lock, seed=config.seed)
        self._status_pub = node.publisher(registry.SIM_POSE_SOURCE)
        self.cameras = (
            make_cameras(
                config, scenario, node, self.world, lambda: self.pose.frame_pose(node.clock.time())
            )
            if config.cameras
            else None
        )
        self.truth_published = 0

    def describe(self) -> str:
        cams = "off" if self.cameras is None else f"{self.cameras.rate_hz:g} Hz"
        return (
            f"scenario {self.scenario.name}, vehicle pose from {self.source} truth on "
            f"{self.link.spec} (asked for {self.link.rate_hz:g} Hz), namespace {self.node.ns}, "
            f"cameras {cams}"
        )

    def run(self, stop: threading.Event, duration_s: float | None = None) -> None:
        """Run until ``stop`` is set (or ``duration_s`` of the node's clock passed)."""
        if self.cameras is not None:
            self.cameras.start()
        clock = self.node.clock
        start = last_step = clock.monotonic()
        obj_period = 1.0 / self.config.object_pose_rate_hz
        next_obj = next_status = start
        next_log = start + LOG_PERIOD_S
        while not stop.is_set():
            now = clock.monotonic()
            if duration_s is not None and now - start >= duration_s:
                break
            self.link.tick(clock.time())
            fd = self.link.fileno()
            if fd >= 0:
                readable, _, _ = select.select([fd], [], [], WORLD_STEP_S)
                if readable:
                    self._receive()
            else:
                clock.wait(stop, WORLD_STEP_S)
            now = clock.monotonic()
            if now - last_step >= WORLD_STEP_S:
                if self.pose.airborne:
                    with self.world_lock:
                        self.world.step(min(now - last_step, MAX_WORLD_STEP_S))
                last_step = now
            if now >= next_obj:
                next_obj = max(next_obj + obj_period, now)
                self.world_topics.publish_objects()
            if now >= next_status:
                next_status = max(next_status + STATUS_PERIOD_S, now)
                status = self.pose.status(self.source, self.link, clock.time())
                self._status_pub.put(status)
                if now >= next_log:
                    next_log = now + LOG_PERIOD_S
                    log.info(
                        "truth %.0f Hz, age now %.0f ms; frames %d, pose age mean %.0f p95 %.0f "
                        "max %.0f ms, %.0f%% extrapolated",
                        status.truth_rate_hz, status.truth_age_s * 1e3, status.frames,
                        status.age_mean_s * 1e3, status.age_p95_s * 1e3, status.age_max_s * 1e3,
                        status.extrapolated_share * 100,
                    )  # fmt: skip

    def _receive(self) -> None:
        arrival = self.node.clock.time()
        for msg in self.link.receive(arrival):
            snapshot = self.pose.add(msg, arrival)
            if snapshot is not None:
                self.truth_published += 1
                self.world_topics.publish_ground_truth(snapshot)

    def close(self) -> None:
        """Stop the camera thread and close the link."""
        if self.cameras is not None and self.cameras.is_alive():
            self.cameras.join(5.0)
        if self.cameras is not None:
            self.cameras.close()
        self.link.close()
