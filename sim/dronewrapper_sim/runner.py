"""The real-time simulator process: autopilot + physics + world, MAVLink on UDP, Zenoh out.

Threads:
- the main loop steps the autopilot and physics at ``physics_rate_hz`` (fixed step, simulated
  time = wall time x ``realtime_factor``), steps the world, answers MAVLink as soon as a
  datagram arrives (``select`` on the link sockets), sends the telemetry due, and publishes
  ``{ns}/sim/ground_truth`` and ``sim/objects/{name}/pose`` on Zenoh. It wakes for the next
  step, or at most ``loop_rate_hz`` times a second (then runs the steps owed at once, and sends
  the telemetry due before the next wake-up's midpoint: a fleet's sims and bridges wake
  fewer times for the same streams). Its wake-ups keep to a grid of ``1 / loop_rate_hz`` on
  the monotonic clock; hosted with other members, the loop is no thread of its own but a
  deadline and sockets of the host's one loop thread (:mod:`dronewrapper_sim.shared_loop`);
- the camera thread renders ``cam_frontal`` and ``cam_ventral`` at the camera rate from a
  snapshot of the true pose and publishes ``{ns}/{camera}/image_raw`` (bgr8) and, while
  someone subscribes (or ``compressed`` is set), ``.../image_raw/compressed`` (JPEG); a camera
  nobody watches is not rendered. ``header.stamp`` is the capture time (wall clock);
- Zenoh callback threads forward ``sim/objects/{name}/cmd_vel`` to the world (teleop).
"""

from __future__ import annotations

import logging
import math
import select
import threading
from pathlib import Path
from typing import Any

from dronewrapper.rotations import quat_from_rpy
from dronewrapper.runtime import ServiceError
from dronewrapper.runtime.clock import REAL, Clock
from dronewrapper.runtime.contract import NodeApi
from dronewrapper.security.keystore import read_mavlink_key
from dronewrapper_sim.camera_stream import CameraStreamer
from dronewrapper_sim.config import SimConfig
from dronewrapper_sim.mavlink_io import MavlinkUdpLink, default_endpoints, parse_udp_spec
from dronewrapper_sim.pose_snapshot import PoseSnapshot
from dronewrapper_sim.px4 import telemetry
from dronewrapper_sim.px4.autopilot import Autopilot, AutopilotConfig
from dronewrapper_sim.px4.signing import SigningPolicy
from dronewrapper_sim.world.scenario import Scenario
from dronewrapper_sim.world_topics import WorldTopics

log = logging.getLogger("sim")

MAX_CATCH_UP_STEPS = 50  # after a stall, at most this many physics steps at once; then slip


def link_endpoints(config: SimConfig) -> dict[str, Any]:
    """The UDP endpoint of each enabled link (None = disabled) for ``config``."""
    defaults = default_endpoints(config.instance)
    out: dict[str, Any] = {}
    for name, spec in (("onboard", config.udp_onboard), ("gcs", config.udp_gcs)):
        default = defaults[name]
        out[name] = parse_udp_spec(spec, default.local_port) if spec else default
    return out


class SimRunner:
    """One simulated vehicle and its world, run in real time (see module doc).

    Args:
        config: the simulator's settings.
        scenario: the world to simulate.
        node: the Zenoh node to publish on (None: MAVLink only, no Zenoh, no cameras).
    """

    def __init__(self, config: SimConfig, scenario: Scenario, node: NodeApi | None) -> None:
        from dronewrapper_sim.world.world import World

        self.config = config
        self.scenario = scenario
        self.node = node
        self.time: Clock = REAL if node is None else node.clock
        """The process's time: the node's clock (the real clocks without a node)."""
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
        key = read_mavlink_key(config.signing_key_file) if config.signing_key_file else None
        self.signing = SigningPolicy(key)
        self._rejections_logged: dict[str, tuple[int, float]] = {}
        self._set_signing_key(key)
        self._snapshot = self._make_snapshot()
        self.cameras: CameraStreamer | None = None
        self.world_topics: WorldTopics | None = None
        self._reset_asked = threading.Event()  # a reset, applied by the loop between steps
        self._reset_done = threading.Event()
        self.slipped_s = 0.0  # wall-clock seconds the simulated clock gave up after stalls
        # (monotonic wall s, simulated s, slipped_s) taken together after each stepping
        self.clock: tuple[float, float, float] = (self.time.monotonic(), 0.0, 0.0)
        if node is not None:
            self._setup_zenoh(node)

    # ---- setup ----

    def _setup_zenoh(self, node: NodeApi) -> None:
        self.world_topics = WorldTopics(
            node, self.world, self.world_lock, seed=self.config.seed, reset_vehicle=self.reset
        )
        if self.config.cameras:
            self.cameras = self._make_cameras(node)

    def _make_cameras(self, node: NodeApi) -> CameraStreamer:
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
        return PoseSnapshot(
            (s.x, s.y, s.z), quat_from_rpy(s.roll, s.pitch, s.yaw), self.time.time()
        )

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

    def reset(self, timeout_s: float = 2.0) -> str:
        """Put the vehicle back at its start pose, disarmed (applied by the loop between two
        physics steps); says what was done.

        Raises:
            ServiceError: the loop did not apply it within ``timeout_s`` (it is not running).
        """
        self._reset_done.clear()
        self._reset_asked.set()
        if not self._reset_done.wait(timeout_s):
            raise ServiceError(f"the simulation loop did not reset within {timeout_s:g} s")
        cfg = self.autopilot.config
        return f"back at its start ({cfg.start_x:g}, {cfg.start_y:g}) m, landed, disarmed"

    # ---- the loop ----

    def run(self, stop: threading.Event, duration_s: float | None = None) -> None:
        """Run until ``stop`` is set (or ``duration_s`` of wall time passed): on a thread of
        its own, or, hosted with other members (:mod:`dronewrapper.runtime.host`) and with no
        ``duration_s``, on the host's shared loop (:mod:`dronewrapper_sim.shared_loop`)."""
        if duration_s is None and self.node is not None:
            from dronewrapper.runtime.host import shared_poller
            from dronewrapper_sim.shared_loop import run_on_poller

            poller = shared_poller()
            if poller is not None:
                run_on_poller(self, poller, stop)
                return
        self.begin()
        start = self.time.monotonic()
        socks = list(self.links.values())
        while not stop.is_set():
            now = self.time.monotonic()
            if duration_s is not None and now - start >= duration_s:
                break
            wait = min(max(self.next_wake() - now, 0.0), 0.05)
            if socks:
                readable, _, _ = select.select(socks, [], [], wait)
                for link in readable:
                    self.receive(link)
            elif wait > 0:
                self.time.wait(stop, wait)
            self.wake(self.time.monotonic())

    def begin(self) -> None:
        """Start the loop's schedule now, and the cameras."""
        if self.cameras is not None:
            self.cameras.start()
        self._dt = 1.0 / self.config.physics_rate_hz
        self._rtf = self.config.realtime_factor
        loop_hz = self.config.loop_rate_hz
        self._gap = 1.0 / loop_hz if loop_hz else 0.0  # wall s between two wake-ups, at least
        # wall s: telemetry sent early, due by the next wake-up's midpoint
        self._ahead = self._gap / 2 if self._gap > self._dt / self._rtf else 0.0
        now = self.time.monotonic()
        self._t0 = now
        self._wake_at = now  # the wake-ups' own schedule (on a grid of ``gap``)
        self._steps = 0
        self._next_gt = self._next_obj = now

    def next_wake(self) -> float:
        """When the loop next has work (monotonic s): the next physics step, no sooner than
        the next wake-up of its schedule."""
        return max(self._t0 + (self._steps + 1) * self._dt / self._rtf, self._wake_at)

    def wake(self, now: float) -> float:
        """At ``now`` (monotonic s), if a step is due: run the steps owed, step the world,
        send the telemetry due and publish what is due on Zenoh. Returns :meth:`next_wake`.

        The wake-ups keep to a grid of ``1 / loop_rate_hz`` on the monotonic clock, so the
        sims of one host (and of one machine) wake at the same instants and their datagrams
        leave together."""
        if now < self.next_wake():
            return self.next_wake()
        dt, rtf = self._dt, self._rtf
        owed = int((now - self._t0) * rtf / dt) - self._steps
        if owed > MAX_CATCH_UP_STEPS:  # a long stall: slip the clock, do not burst
            slip = (owed - MAX_CATCH_UP_STEPS) * dt / rtf
            self._t0 += slip
            self.slipped_s += slip
            owed = MAX_CATCH_UP_STEPS
        if self._reset_asked.is_set():
            self._reset_asked.clear()
            self.autopilot.reset_to_start()
            self._reset_done.set()
        for _ in range(owed):
            self.autopilot.step(dt)
        self._steps += owed
        gap = self._gap
        self._wake_at = gap * (math.floor(now / gap) + 1) if gap else now
        self.clock = (now, self.autopilot.time_s, self.slipped_s)
        with self.world_lock:
            self.world.step(owed * dt)
        self._snapshot = self._make_snapshot()
        ahead = self._ahead
        for name, msgs in self.autopilot.poll(ahead * rtf).items():
            if msgs:
                self.links[name].send(msgs)
        if now + ahead >= self._next_gt:
            self._next_gt = max(self._next_gt + 1.0 / self.config.ground_truth_rate_hz, now)
            self._publish_ground_truth()
        if now + ahead >= self._next_obj:
            self._next_obj = max(self._next_obj + 1.0 / self.config.object_pose_rate_hz, now)
            self._publish_objects()
        return self.next_wake()

    def _set_signing_key(self, key: bytes | None) -> None:
        for link in self.links.values():
            link.set_signing_key(key, self.signing.allow_unsigned, self.time.time())

    def _setup_signing(self, link: MavlinkUdpLink, msg: Any) -> None:
        if msg.target_system not in (0, self.autopilot.sysid):
            return
        decision = self.signing.setup_signing(
            bytes(msg.secret_key),
            signed=bool(getattr(msg, "_signed", False)),
            armed=self.autopilot.armed,
        )
        log.warning("%s link: SETUP_SIGNING %s", link.name, decision.reason)
        if decision.accepted:
            self._set_signing_key(decision.key)

    def _note_rejections(self, link: MavlinkUdpLink) -> None:
        rejected, now = link.rejected, self.time.monotonic()
        logged, at = self._rejections_logged.get(link.name, (0, -math.inf))
        if rejected > logged and now - at >= 2.0:
            self._rejections_logged[link.name] = (rejected, now)
            log.warning(
                "%s link: %d message(s) rejected so far (unsigned, wrongly signed or replayed)",
                link.name,
                rejected,
            )

    def receive(self, link: MavlinkUdpLink) -> None:
        """Handle every message waiting on ``link`` (the autopilot answers at once)."""
        msgs = link.receive()
        if link.rejected:
            self._note_rejections(link)
        for msg in msgs:
            if msg.get_type() == "SETUP_SIGNING":
                self._setup_signing(link, msg)
                continue
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
