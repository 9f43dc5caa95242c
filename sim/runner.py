"""The real-time simulator process: autopilot + physics + world, MAVLink on UDP, Zenoh out.

Threads:
- the main loop steps the autopilot and physics at ``physics_rate_hz`` (fixed step, simulated
  time = wall time x ``realtime_factor``), steps the world, answers MAVLink as soon as a
  datagram arrives (``select`` on the link sockets), sends the telemetry due, and publishes
  ``{ns}/sim/ground_truth`` and ``sim/objects/{name}/pose`` on Zenoh;
- the camera thread renders ``cam_frontal`` and ``cam_ventral`` at the camera rate from a
  snapshot of the true pose and publishes ``{ns}/{camera}/image_raw`` (bgr8) and, while
  someone subscribes (or ``compressed`` is set), ``.../image_raw/compressed`` (JPEG); a camera
  nobody watches is not rendered. ``header.stamp`` is the capture time (wall clock);
- Zenoh callback threads forward ``sim/objects/{name}/cmd_vel`` to the world (teleop).
"""

from __future__ import annotations

import contextlib
import logging
import math
import select
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import zenoh

from dronewrapper.msgs import codec, registry
from dronewrapper.msgs.geometry import Point, Pose, PoseStamped, Quaternion, Twist
from dronewrapper.msgs.sensor import CompressedImage, Image
from dronewrapper.msgs.std import Header
from dronewrapper.runtime import Node, Ratekeeper, encoding_for
from dronewrapper_sim.config import SimConfig
from dronewrapper_sim.frames import quat_from_euler
from dronewrapper_sim.mavlink_io import MavlinkUdpLink, default_endpoints, parse_udp_spec
from dronewrapper_sim.px4 import telemetry
from dronewrapper_sim.px4.autopilot import Autopilot, AutopilotConfig
from dronewrapper_sim.world.scenario import Scenario

log = logging.getLogger("sim")

MAX_CATCH_UP_STEPS = 50  # after a stall, at most this many physics steps at once; then slip


@dataclass(frozen=True)
class PoseSnapshot:
    """The true vehicle pose at one instant: ENU position (m), quaternion x y z w (FLU->ENU),
    wall-clock time (s since the epoch)."""

    position: tuple[float, float, float]
    quaternion: tuple[float, float, float, float]
    stamp: float


def pose_msg(snapshot: PoseSnapshot, frame_id: str = "map", seq: int = 0) -> PoseStamped:
    """A PoseStamped of ``snapshot`` in local ENU."""
    x, y, z = snapshot.position
    qx, qy, qz, qw = snapshot.quaternion
    return PoseStamped(
        header=Header(stamp=snapshot.stamp, frame_id=frame_id, seq=seq),
        pose=Pose(position=Point(x=x, y=y, z=z), orientation=Quaternion(x=qx, y=qy, z=qz, w=qw)),
    )


def link_endpoints(config: SimConfig) -> dict[str, Any]:
    """The UDP endpoint of each enabled link (None = disabled) for ``config``."""
    defaults = default_endpoints(config.instance)
    out: dict[str, Any] = {}
    for name, spec in (("onboard", config.udp_onboard), ("gcs", config.udp_gcs)):
        default = defaults[name]
        out[name] = parse_udp_spec(spec, default.local_port) if spec else default
    return out


class _WatchedPublisher:
    """A Zenoh publisher that knows whether any subscriber matches it."""

    def __init__(self, session: zenoh.Session, key: str, msg_type: type) -> None:
        self.key = key
        self.count = 0
        self._pub = session.declare_publisher(key, encoding=encoding_for(msg_type))

    def watched(self) -> bool:
        try:
            return bool(self._pub.matching_status.matching)
        except zenoh.ZError:
            return False

    def put(self, msg: Any) -> None:
        self._pub.put(codec.encode(msg))
        self.count += 1

    def undeclare(self) -> None:
        with contextlib.suppress(zenoh.ZError):
            self._pub.undeclare()


class CameraStreamer(threading.Thread):
    """Renders and publishes the cameras at a fixed rate (see module doc)."""

    def __init__(
        self,
        node: Node,
        renderer: Any,
        mounts: list[Any],
        rate_hz: float,
        pose_source: Callable[[], PoseSnapshot],
        *,
        compressed: bool = False,
        jpeg_quality: int = 80,
        render_unwatched: bool = False,
    ) -> None:
        super().__init__(name="sim-cameras", daemon=True)
        self.node = node
        self.renderer = renderer
        self.mounts = mounts
        self.rate_hz = rate_hz
        self.pose_source = pose_source
        self.compressed = compressed
        self.jpeg_quality = jpeg_quality
        self.render_unwatched = render_unwatched
        self.frames = {m.name: 0 for m in mounts}
        self.render_s = 0.0
        self.errors = 0
        ns = node.ns
        self._raw = {
            m.name: _WatchedPublisher(
                node.session, registry.IMAGE_RAW.key(ns, camera=m.name), Image
            )
            for m in mounts
        }
        self._jpeg = {
            m.name: _WatchedPublisher(
                node.session, registry.IMAGE_COMPRESSED.key(ns, camera=m.name), CompressedImage
            )
            for m in mounts
        }

    def run(self) -> None:
        rate = Ratekeeper(self.rate_hz, stop=self.node.stop_event)
        while rate.sleep():
            for mount in self.mounts:
                try:
                    self._one(mount)
                except Exception:  # a rendering bug must not stop the simulator
                    self.errors += 1
                    if self.errors <= 3:
                        log.exception("camera %s failed", mount.name)

    def _one(self, mount: Any) -> None:
        raw, jpeg = self._raw[mount.name], self._jpeg[mount.name]
        want_raw = self.render_unwatched or raw.watched()
        want_jpeg = self.compressed or jpeg.watched()
        if not (want_raw or want_jpeg):
            return
        snap = self.pose_source()
        stamp = time.time()
        started = time.perf_counter()
        image = self.renderer.render(mount, np.asarray(snap.position), np.asarray(snap.quaternion))
        self.render_s += time.perf_counter() - started
        seq = self.frames[mount.name]
        self.frames[mount.name] = seq + 1
        header = Header(stamp=stamp, frame_id=mount.name, seq=seq)
        height, width = image.shape[:2]
        if want_raw:
            raw.put(
                Image(
                    header=header,
                    height=height,
                    width=width,
                    encoding="bgr8",
                    step=width * 3,
                    data=image.tobytes(),
                )
            )
        if want_jpeg:
            import cv2

            ok, buf = cv2.imencode(".jpg", image, [cv2.IMWRITE_JPEG_QUALITY, self.jpeg_quality])
            if ok:
                jpeg.put(CompressedImage(header=header, format="jpeg", data=buf.tobytes()))

    def close(self) -> None:
        for pub in [*self._raw.values(), *self._jpeg.values()]:
            pub.undeclare()


class WorldTopics:
    """The world on Zenoh, the same for every aircraft: the vehicle's ``{ns}/sim/ground_truth``,
    ``sim/objects/{name}/pose`` of each object, and their teleop ``sim/objects/{name}/cmd_vel``.

    Args:
        node: the Zenoh node.
        world: the world whose objects are published and teleoperated.
        world_lock: the lock the simulation holds while it steps ``world``.
    """

    def __init__(self, node: Node, world: Any, world_lock: threading.Lock) -> None:
        self.world = world
        self.world_lock = world_lock
        self.cmd_vel_errors = 0
        self._gt_pub = node.publisher(registry.SIM_GROUND_TRUTH)
        self._object_pubs: dict[str, Any] = {}
        for obj in world.objects:
            self._object_pubs[obj.name] = node.publisher(registry.SIM_OBJECT_POSE, name=obj.name)
            node.subscribe(
                registry.SIM_OBJECT_CMD_VEL, self._teleop_callback(obj.name), name=obj.name
            )

    def publish_ground_truth(self, snapshot: PoseSnapshot) -> None:
        """Publish the vehicle's true pose."""
        self._gt_pub.put(pose_msg(snapshot, seq=self._gt_pub.count))

    def publish_objects(self) -> None:
        """Publish the true pose of every world object (stamped now)."""
        stamp = time.time()
        for obj in self.world.objects:
            pub = self._object_pubs.get(obj.name)
            if pub is None:
                continue
            x, y, z = (float(v) for v in obj.position)
            snap = PoseSnapshot((x, y, z), quat_from_euler(0.0, 0.0, float(obj.yaw)), stamp)
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


class SimRunner:
    """One simulated vehicle and its world, run in real time (see module doc).

    Args:
        config: the simulator's settings.
        scenario: the world to simulate.
        node: the Zenoh node to publish on (None: MAVLink only, no Zenoh, no cameras).
    """

    def __init__(self, config: SimConfig, scenario: Scenario, node: Node | None) -> None:
        from dronewrapper_sim.world.world import World

        self.config = config
        self.scenario = scenario
        self.node = node
        seed = scenario.seed if config.seed is None else config.seed
        self.world = World(scenario, seed=seed)
        self.world_lock = threading.Lock()
        endpoints = link_endpoints(config)
        rates = {"onboard": telemetry.ONBOARD_RATES, "gcs": telemetry.GCS_RATES}
        self.autopilot = Autopilot(
            AutopilotConfig(
                sysid=1 + config.instance,
                home_lat_deg=scenario.home.latitude_deg,
                home_lon_deg=scenario.home.longitude_deg,
                home_alt_m=scenario.home.altitude_m,
                start_x=scenario.vehicle.x,
                start_y=scenario.vehicle.y,
                start_yaw=scenario.vehicle.yaw,
                wind_east=scenario.wind.east_m_s,
                wind_north=scenario.wind.north_m_s,
                wind_gust=scenario.wind.gust_m_s,
                seed=seed,
                params=dict(config.params),
            ),
            link_rates={name: rates[name] for name, ep in endpoints.items() if ep is not None},
        )
        self.links: dict[str, MavlinkUdpLink] = {}
        try:
            for name, ep in endpoints.items():
                if ep is not None:
                    self.links[name] = MavlinkUdpLink(name, ep, sysid=1 + config.instance)
        except OSError:
            self.close()
            raise
        self._snapshot = self._make_snapshot()
        self.cameras: CameraStreamer | None = None
        self.world_topics: WorldTopics | None = None
        self.slipped_s = 0.0  # wall-clock seconds the simulated clock gave up after stalls
        # (monotonic wall s, simulated s, slipped_s) taken together after each stepping
        self.clock: tuple[float, float, float] = (time.monotonic(), 0.0, 0.0)
        if node is not None:
            self._setup_zenoh(node)

    # ---- setup ----

    def _setup_zenoh(self, node: Node) -> None:
        self.world_topics = WorldTopics(node, self.world, self.world_lock)
        if self.config.cameras:
            self.cameras = self._make_cameras(node)

    def _make_cameras(self, node: Node) -> CameraStreamer:
        from dronewrapper_sim.render.camera import FRONTAL, VENTRAL, PinholeCamera
        from dronewrapper_sim.render.renderer import Renderer

        cam = self.scenario.camera
        camera = PinholeCamera(
            width=self.config.width or cam.width,
            height=self.config.height or cam.height,
            hfov_rad=math.radians(cam.hfov_deg),
        )
        sprites = Path(self.config.sprites) if self.config.sprites else None
        renderer = Renderer(self.world, camera, sprites_dir=sprites)
        return CameraStreamer(
            node,
            renderer,
            [FRONTAL, VENTRAL],
            self.config.camera_rate_hz or cam.rate_hz,
            lambda: self._snapshot,
            compressed=self.config.compressed,
            jpeg_quality=self.config.jpeg_quality,
            render_unwatched=self.config.render_unwatched,
        )

    @property
    def cmd_vel_errors(self) -> int:
        """Teleop commands refused (unknown object, bad values)."""
        return self.world_topics.cmd_vel_errors if self.world_topics else 0

    def _make_snapshot(self) -> PoseSnapshot:
        s = self.autopilot.state
        return PoseSnapshot((s.x, s.y, s.z), quat_from_euler(s.roll, s.pitch, s.yaw), time.time())

    def describe(self) -> str:
        """One line saying what runs where."""
        links = ", ".join(
            f"{name} -> {link.remote[0]}:{link.remote[1]} from :{link.local_port}"
            for name, link in self.links.items()
        )
        ns = self.node.ns if self.node else "-"
        cams = "off" if self.cameras is None else f"{self.cameras.rate_hz:g} Hz"
        return (
            f"scenario {self.scenario.name}, sysid {self.autopilot.sysid}, namespace {ns}, "
            f"MAVLink {links or 'off'}, cameras {cams}"
        )

    # ---- the loop ----

    def run(self, stop: threading.Event, duration_s: float | None = None) -> None:
        """Run until ``stop`` is set (or ``duration_s`` of wall time passed)."""
        if self.cameras is not None:
            self.cameras.start()
        dt = 1.0 / self.config.physics_rate_hz
        rtf = self.config.realtime_factor
        start = time.monotonic()
        t0 = start
        steps = 0
        gt_period = 1.0 / self.config.ground_truth_rate_hz
        obj_period = 1.0 / self.config.object_pose_rate_hz
        next_gt = next_obj = start
        socks = list(self.links.values())
        while not stop.is_set():
            now = time.monotonic()
            if duration_s is not None and now - start >= duration_s:
                break
            next_tick = t0 + (steps + 1) * dt / rtf
            wait = min(max(next_tick - now, 0.0), 0.05)
            if socks:
                readable, _, _ = select.select(socks, [], [], wait)
                for link in readable:
                    self._receive(link)
            elif wait > 0:
                stop.wait(wait)
            now = time.monotonic()
            if now < next_tick:
                continue
            owed = int((now - t0) * rtf / dt) - steps
            if owed > MAX_CATCH_UP_STEPS:  # a long stall: slip the clock, do not burst
                slip = (owed - MAX_CATCH_UP_STEPS) * dt / rtf
                t0 += slip
                self.slipped_s += slip
                owed = MAX_CATCH_UP_STEPS
            for _ in range(owed):
                self.autopilot.step(dt)
            steps += owed
            self.clock = (now, self.autopilot.time_s, self.slipped_s)
            with self.world_lock:
                self.world.step(owed * dt)
            self._snapshot = self._make_snapshot()
            for name, msgs in self.autopilot.poll().items():
                if msgs:
                    self.links[name].send(msgs)
            if now >= next_gt:
                next_gt = max(next_gt + gt_period, now)
                self._publish_ground_truth()
            if now >= next_obj:
                next_obj = max(next_obj + obj_period, now)
                self._publish_objects()

    def _receive(self, link: MavlinkUdpLink) -> None:
        for msg in link.receive():
            try:
                replies = self.autopilot.handle(link.name, msg)
            except Exception:  # a message the autopilot cannot digest must not stop it
                log.exception("%s link: failed to handle %s", link.name, msg.get_type())
                continue
            if replies:
                link.send(replies)

    def _publish_ground_truth(self) -> None:
        if self.world_topics is not None:
            self.world_topics.publish_ground_truth(self._snapshot)

    def _publish_objects(self) -> None:
        if self.world_topics is not None:
            self.world_topics.publish_objects()

    def close(self) -> None:
        """Stop the camera thread and close the sockets."""
        if self.cameras is not None and self.cameras.is_alive():
            self.cameras.join(5.0)
        if self.cameras is not None:
            self.cameras.close()
        for link in self.links.values():
            link.close()
