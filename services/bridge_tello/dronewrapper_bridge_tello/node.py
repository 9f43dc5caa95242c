"""The bridge process: a Tello (SDK 2.0 over UDP) <-> MAVROS-equivalent Zenoh keys (README.md).

Only I/O here: the three sockets, the video, the threads. Everything the bridge decides (the
commander lease included) is in :class:`~dronewrapper_bridge_tello.core.TelloCore` (pure, time
as an argument); the wiring every bridge shares (driver, publishers, services, setpoints, tick
loop) is :class:`~dronewrapper_bridge_base.bridge_node.BridgeNode`. Threads: replies
(command socket -> core), state (state strings -> core), control at ``rc_rate_hz`` (the core's
tick: failsafe, ``rc`` sticks, keep-alive, link supervision, periodic State, and the video's
``streamon``/``streamoff`` as the camera's subscribers come and go), video (datagrams -> decoder
-> newest frame) and its publisher, plus the Node's service workers, which start an operation in
the core and wait until it is done. Time is the node's clock alone: the core starts at it, the
driver and the loops read and wait on it, and it makes the loops' threads.
"""

from __future__ import annotations

import functools
import logging
import threading
from collections.abc import Callable
from typing import Any

from dronewrapper.images import bgr_to_image, bgr_to_jpeg
from dronewrapper.msgs import registry
from dronewrapper.msgs.mavros import State
from dronewrapper.msgs.registry import Service
from dronewrapper.runtime import Latest, Node, Ratekeeper
from dronewrapper.runtime.contract import NodeApi
from dronewrapper.runtime.ports import Ports
from dronewrapper.security.wifi import open_wifi_warning
from dronewrapper_bridge_base.bridge_node import (
    BRIDGE_PUBLISHED,
    BridgeNode,
    Operation,
    bridge_ports,
)
from dronewrapper_bridge_tello import actions, flight, missions
from dronewrapper_bridge_tello import operations as ops
from dronewrapper_bridge_tello.camera_watch import CameraWatch
from dronewrapper_bridge_tello.config import Config
from dronewrapper_bridge_tello.core import Outbox, TelloCore
from dronewrapper_bridge_tello.link import TelloAddress, TelloLink
from dronewrapper_bridge_tello.video import VideoReceiver
from dronewrapper_bridge_tello.video_demand import OFF

log = logging.getLogger("bridge_tello")

VIDEO_DATAGRAM = 65535
"""The largest video datagram read (bytes); replies and state strings fit in 2048."""

PUBLISHED = (
    *BRIDGE_PUBLISHED,
    registry.MISSION_WAYPOINTS,
    registry.MISSION_REACHED,
)
SERVICES: dict[Service[Any, Any], Operation] = {
    registry.FLIGHT_TAKEOFF: flight.takeoff_to,
    registry.FLIGHT_LAND: flight.land_here,
    registry.FLIGHT_GOTO: actions.goto_point,
    registry.FLIGHT_RETURN: actions.return_home,
    registry.FLIGHT_MISSION: actions.mission_action,
    registry.ARMING: ops.arming,
    registry.TAKEOFF: ops.takeoff,
    registry.LAND: ops.land,
    registry.SET_MODE: ops.set_mode,
    registry.PARAM_GET: ops.param_get,
    registry.PARAM_SET: ops.param_set,
}


def serve_services(bridge: BridgeNode[Any]) -> None:
    """Serve this bridge's services on ``bridge``: :data:`SERVICES`, and
    ``missions.SERVICES`` (the mission services and the envelope), which only the command
    lease's holder may call."""
    bridge.serve(SERVICES, missions.SERVICES)


PORTS = bridge_ports("bridge_tello", PUBLISHED, SERVICES, missions.SERVICES) | Ports(
    "bridge_tello", publishes=(registry.IMAGE_RAW, registry.IMAGE_COMPRESSED)
)
"""What this bridge publishes, subscribes to and serves (:mod:`dronewrapper.runtime.ports`)."""


class Bridge(BridgeNode[TelloCore]):
    """The core wired to one Node and one Tello (its three sockets open at construction:
    ``OSError`` when an address is taken; ``link``: one already made instead)."""

    def __init__(self, node: NodeApi, config: Config, link: TelloLink | None = None) -> None:
        publishers = {topic: node.publisher(topic) for topic in PUBLISHED}
        super().__init__(node, TelloCore(config, node.clock.monotonic()), publishers, log)
        self.config = config
        self.link = link or TelloLink(TelloAddress.of(config), video=config.video != OFF)
        self.pub_image = node.publisher(registry.IMAGE_RAW, camera="cam_frontal")
        self.pub_jpeg = node.publisher(registry.IMAGE_COMPRESSED, camera="cam_frontal")
        self.camera = CameraWatch([self.pub_image, self.pub_jpeg] if config.video != OFF else [])
        self.receiver = VideoReceiver(chunk=config.video_chunk)
        self._runs = 0  # streamons sent: the video thread restarts its receiver at each
        self._video_run = 0  # the run the receiver decodes (video thread)
        # the newest decoded frame and its stamp: the publisher skips what it could not keep up with
        self.newest: Latest[tuple[Any, float]] = Latest("decoded frame", node.clock)
        self.frames_published = 0

    # ---- what the core knows

    def state_message(self) -> State:
        """The State the bridge publishes now."""
        with self.driver.cond:
            return self.core.state_message()

    # ---- feeding the core

    def send(self, out: Outbox) -> None:
        if out.video_restart:
            self._runs += 1  # the video thread restarts its receiver
        for text in out.sends:
            try:
                self.link.send(text)
            except OSError as exc:
                log.warning("cannot send %r: %s", text, exc)

    # ---- lifecycle

    def start(self) -> list[threading.Thread]:
        """Subscribe, serve, and start the loops (returns the threads)."""
        serve_services(self)
        loops: list[tuple[Callable[..., None], tuple[Any, ...], str]] = [
            (self._receive_loop, (self.link.command, self._on_reply, "replies"), "tello-replies"),
            (self._receive_loop, (self.link.state, self._on_state, "state"), "tello-state"),
            (self._control_loop, (), "tello-control"),
        ]
        if self.config.video != OFF:
            video = (self.link.video, self._on_video, "video", VIDEO_DATAGRAM)
            loops += [
                (self._receive_loop, video, "tello-video"),
                (self._image_loop, (), "tello-images"),
            ]
        clock = self.node.clock
        threads = [clock.thread(functools.partial(f, *a), n) for f, a, n in loops]
        for thread in threads:
            thread.start()
        self.driver.feed(self.core.on_started)
        return threads

    def _control_loop(self) -> None:
        """The core's tick at ``rc_rate_hz`` with whether the camera is watched (errors counted
        under ``control`` and logged; the loop goes on)."""
        rate = Ratekeeper(self.config.rc_rate_hz, stop=self.node.stop_event, clock=self.node.clock)
        while rate.sleep():
            try:
                self.driver.feed(self.core.tick, camera_watched=self.camera.watched)
            except Exception:
                self.node.callback_errors["control"] += 1
                log.exception("control loop error")

    def _on_reply(self, data: bytes) -> None:
        self.driver.feed(self.core.on_reply, data.decode("utf-8", "replace"))

    def _on_state(self, data: bytes) -> None:
        self.driver.feed(self.core.on_state, data)

    def _receive_loop(
        self, sock: Any, handle: Callable[[bytes], None], what: str, size: int = 2048
    ) -> None:
        """Every datagram of ``sock`` (up to ``size`` bytes) to ``handle`` (errors counted
        under ``what``)."""
        clock, stop = self.node.clock, self.node.stop_event
        while not stop.is_set():
            try:
                data, _ = sock.recvfrom(size)
            except TimeoutError:
                continue
            except OSError:
                if clock.wait(stop, 0.2):
                    return
                continue
            try:
                handle(data)
            except Exception:
                self.node.callback_errors[what] += 1
                log.exception("error handling a %s datagram", what)

    # ---- video

    def _jpeg_wanted(self) -> bool:
        """JPEG when configured, or while a subscriber matches image_raw/compressed."""
        return self.config.compressed or self.pub_jpeg.watched()

    def _on_video(self, data: bytes) -> None:
        """One video datagram to the decoder; each decoded frame becomes the newest, stamped
        with its arrival (a streamon sent since the last one: a clean start at its key frame)."""
        if self._video_run != self._runs:
            self._video_run = self._runs
            self.receiver.restart()
        stamp = self.node.clock.time()
        for decoded in self.receiver.feed(data):
            self.newest.update((decoded, stamp))

    def _image_loop(self) -> None:
        stop = self.node.stop_event
        seq = taken = 0
        while not stop.is_set():
            item = self.newest.take(0.2, newer_than=taken)
            if item is None:
                continue
            taken, (frame, stamp) = item
            try:
                image = frame.to_ndarray(format="bgr24")
            except Exception:
                self.receiver.counts.corrupt += 1
                continue
            self.pub_image.put(bgr_to_image(image, stamp, "cam_frontal", seq))  # a view: no copy
            if self._jpeg_wanted():
                jpeg = bgr_to_jpeg(image, stamp, "cam_frontal", seq, self.config.jpeg_quality)
                self.pub_jpeg.put(jpeg)
            seq += 1
            self.frames_published += 1


def run(node: Node, config: Config) -> int:
    """The service body: open the sockets, start the bridge, announce readiness, run."""
    try:
        bridge = Bridge(node, config)
    except OSError as exc:
        log.error("cannot open the Tello sockets on %s: %s", config.local_address, exc)
        return 1
    threads = bridge.start()
    node.announce()
    warning = open_wifi_warning()  # a Tello's Wi-Fi is open until a password is set
    if warning:
        log.warning("%s", warning)
    log.info(
        "bridge_tello ready: Tello %s:%d, listening on %s (namespace %s)",
        config.tello_address,
        config.command_port,
        config.local_address,
        node.ns,
    )
    node.spin()
    for thread in threads:
        thread.join(timeout=2.0)
    bridge.camera.close()
    bridge.link.close()
    return 0


__all__ = ["Bridge", "Config", "run"]
