"""The cameras' thread: renders the frontal and ventral images from the vehicle's pose at the
camera rate and publishes them (raw or JPEG, each while someone subscribes to it) through the
node's publishers (the registry's QoS; raw frames written straight into shared memory when the
node has it). Stamps and pacing are on the node's clock."""

from __future__ import annotations

import contextlib
import logging
import threading
import time
from collections.abc import Callable
from typing import Any

import numpy as np

from dronewrapper.images import bgr_to_image, bgr_to_jpeg
from dronewrapper.msgs import registry
from dronewrapper.runtime import Ratekeeper
from dronewrapper.runtime.contract import Declared, NodeApi
from dronewrapper_sim.pose_snapshot import PoseSnapshot

log = logging.getLogger("sim")


class CameraStreamer(threading.Thread):
    """Renders and publishes the cameras at a fixed rate (see module doc)."""

    def __init__(
        self,
        node: NodeApi,
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
        self._raw = {m.name: node.publisher(registry.IMAGE_RAW, camera=m.name) for m in mounts}
        self._jpeg = {
            m.name: node.publisher(registry.IMAGE_COMPRESSED, camera=m.name) for m in mounts
        }

    def run(self) -> None:
        rate = Ratekeeper(self.rate_hz, stop=self.node.stop_event, clock=self.node.clock)
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
        stamp = self.node.clock.time()
        started = time.perf_counter()  # the render's CPU cost, not the simulation's time
        image = self.renderer.render(mount, np.asarray(snap.position), np.asarray(snap.quaternion))
        self.render_s += time.perf_counter() - started
        seq = self.frames[mount.name]
        self.frames[mount.name] = seq + 1
        if want_raw:
            raw.put(bgr_to_image(image, stamp, mount.name, seq))  # a view: no copy
        if want_jpeg:
            jpeg.put(bgr_to_jpeg(image, stamp, mount.name, seq, self.jpeg_quality))

    def close(self) -> None:
        pubs: list[Declared] = [*self._raw.values(), *self._jpeg.values()]
        for pub in pubs:
            with contextlib.suppress(Exception):  # already gone with the session
                pub.undeclare()
