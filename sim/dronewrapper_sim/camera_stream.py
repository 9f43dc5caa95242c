"""The cameras' thread: renders the frontal and ventral images from the vehicle's pose at the
camera rate and publishes them (raw or JPEG, each while someone subscribes to it)."""

from __future__ import annotations

import contextlib
import logging
import threading
import time
from collections.abc import Callable
from typing import Any

import numpy as np
import zenoh

from dronewrapper.images import bgr_to_image, bgr_to_jpeg
from dronewrapper.msgs import codec, registry
from dronewrapper.msgs.sensor import CompressedImage, Image
from dronewrapper.runtime import Node, Ratekeeper, encoding_for
from dronewrapper_sim.pose_snapshot import PoseSnapshot

log = logging.getLogger("sim")


class _WatchedPublisher:
    """A Zenoh publisher that knows whether any subscriber matches it."""

    def __init__(self, session: zenoh.Session, key: str, msg_type: type, shm=None) -> None:
        self.key = key
        self.count = 0
        self._shm = shm  # the node's ShmWriter: frames written straight into shared memory
        self._pub = session.declare_publisher(key, encoding=encoding_for(msg_type))

    def watched(self) -> bool:
        try:
            return bool(self._pub.matching_status.matching)
        except zenoh.ZError:
            return False

    def put(self, msg: Any) -> None:
        payload = self._shm.payload(msg) if self._shm is not None else None
        self._pub.put(codec.encode(msg) if payload is None else payload)
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
                node.session,
                registry.IMAGE_RAW.key(ns, camera=m.name),
                Image,
                getattr(node, "shm_writer", None),
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
        if want_raw:
            raw.put(bgr_to_image(image, stamp, mount.name, seq))  # a view: no copy
        if want_jpeg:
            jpeg.put(bgr_to_jpeg(image, stamp, mount.name, seq, self.jpeg_quality))

    def close(self) -> None:
        for pub in [*self._raw.values(), *self._jpeg.values()]:
            pub.undeclare()
