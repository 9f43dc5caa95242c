"""The Tello's video: the forward camera rendered from the true pose, H.264, over UDP.

:class:`H264Encoder` turns BGR images into H.264 Annex-B access units with libx264 (PyAV)
tuned for zero latency (no B-frames, no look-ahead), a key frame every ``keyframe_interval``
frames, each key frame carrying SPS and PPS so that a decoder can join at any key frame; one
thread (no slice threads), the rate capped by a one-second VBV buffer.
:func:`packetise` cuts an access unit into datagrams of at most 1460 bytes, as the real Tello
sends its stream (a frame's last datagram is the short one). :class:`VideoStreamer` is the
thread that renders, encodes and sends at the frame rate while ``streamon`` is in force; it logs
each start (``video: streaming to HOST:PORT``) and stop (``video: stream off after N frames``)
of the stream, and ``runs`` counts the starts.
"""

from __future__ import annotations

import contextlib
import logging
import socket
import threading
import time
from collections.abc import Callable
from fractions import Fraction
from typing import Any

import numpy as np

from dronewrapper.runtime import Ratekeeper

log = logging.getLogger("sim.tello")


class H264Encoder:
    """libx264 through PyAV: BGR images in, Annex-B access units out.

    Args:
        width, height: image size, px (even).
        fps: frame rate, Hz.
        bitrate_kbps: target bit rate, kbit/s.
        keyframe_interval: frames between key frames.
    """

    def __init__(
        self, width: int, height: int, fps: float, bitrate_kbps: int, keyframe_interval: int
    ) -> None:
        import av

        self.width, self.height = width, height
        codec = av.CodecContext.create("libx264", "w")
        codec.width = width
        codec.height = height
        codec.pix_fmt = "yuv420p"
        rate = Fraction(fps).limit_denominator(1000)
        codec.time_base = 1 / rate
        codec.framerate = rate
        codec.bit_rate = bitrate_kbps * 1000
        codec.gop_size = keyframe_interval
        codec.max_b_frames = 0
        codec.options = {
            "preset": "ultrafast",
            "tune": "zerolatency",
            "x264-params": (
                f"repeat-headers=1:keyint={keyframe_interval}:scenecut=0:threads=1:"
                f"vbv-maxrate={bitrate_kbps}:vbv-bufsize={bitrate_kbps}"
            ),
        }
        self._codec = codec
        self._av = av
        self.frames = 0

    def encode(self, image_bgr: np.ndarray) -> bytes:
        """The access unit (Annex-B, start codes) of one image (H x W x 3 uint8 BGR)."""
        if image_bgr.shape != (self.height, self.width, 3):
            raise ValueError(f"image is {image_bgr.shape}, expected {self.height}x{self.width}x3")
        frame = self._av.VideoFrame.from_ndarray(image_bgr, format="bgr24")
        frame.pts = self.frames
        self.frames += 1
        return b"".join(bytes(packet) for packet in self._codec.encode(frame))

    def close(self) -> None:
        with contextlib.suppress(Exception):
            self._codec.encode(None)  # flush


def packetise(access_unit: bytes, packet_bytes: int = 1460) -> list[bytes]:
    """``access_unit`` cut into datagrams of at most ``packet_bytes`` bytes, in order."""
    if packet_bytes < 1:
        raise ValueError(f"packet_bytes must be >= 1, got {packet_bytes}")
    return [access_unit[i : i + packet_bytes] for i in range(0, len(access_unit), packet_bytes)]


class VideoStreamer(threading.Thread):
    """Renders the forward camera, encodes and sends it while the protocol streams.

    Args:
        server: the :class:`~dronewrapper_sim.tello.server.TelloServer` (world, pose, session).
        sprites: folder of person sprites, or None for procedural people.
        make_socket: runs a socket factory where the command socket lives (its namespace).
    """

    def __init__(
        self,
        server: Any,
        sprites: str | None,
        make_socket: Callable[[Callable[[], socket.socket]], socket.socket],
    ) -> None:
        super().__init__(name="tello-video", daemon=True)
        from pathlib import Path

        from dronewrapper_sim.render.camera import FRONTAL, PinholeCamera
        from dronewrapper_sim.render.renderer import Renderer
        from dronewrapper_sim.tello.params import camera_hfov_rad

        cfg = server.config
        self.server = server
        self.config = cfg
        render_w = max(16, round(cfg.width * cfg.render_scale))
        render_h = max(16, round(cfg.height * cfg.render_scale))
        camera = PinholeCamera(render_w, render_h, camera_hfov_rad(cfg.width, cfg.height))
        self.renderer = Renderer(
            server.world, camera, sprites_dir=Path(sprites) if sprites else None
        )
        self.mount = FRONTAL
        host = server.address[0]

        def video_socket() -> socket.socket:
            sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
            sock.bind((host, 0))
            sock.settimeout(0.5)
            return sock

        self.sock = make_socket(video_socket)
        self.stop_event = threading.Event()
        self.encoder: H264Encoder | None = None
        self.frames = 0
        self.datagrams = 0
        self.runs = 0  # starts of the stream (streamon after streamoff or power-on)
        self._run_frames = 0  # frames sent in this run
        self.send_errors = 0
        self.errors = 0
        self.encode_s = 0.0  # render + encode + send, s, all frames
        self.latency_s: list[float] = []  # encode start -> last datagram sent, s (last 300)

    def run(self) -> None:
        stop = self.stop_event
        rate = Ratekeeper(self.config.fps, stop=stop)
        while rate.sleep():
            session = self.server.protocol.session
            if not (session.streaming and session.client is not None):
                if self.encoder is not None:  # streamoff: the next streamon starts afresh
                    self.encoder.close()
                    self.encoder = None
                    log.info("video: stream off after %d frames", self._run_frames)
                continue
            destination = (session.client[0], session.video_port)
            try:
                if self.encoder is None:  # streamon: a new run, starting with a key frame
                    cfg = self.config
                    self.encoder = H264Encoder(
                        cfg.width, cfg.height, cfg.fps, cfg.bitrate_kbps, cfg.keyframe_interval
                    )
                    self.runs += 1
                    self._run_frames = 0
                    log.info("video: streaming to %s:%d", *destination)
                self._one(destination)
            except Exception:  # a rendering or encoding bug must not stop the simulator
                self.errors += 1
                if self.errors <= 3:
                    log.exception("video frame failed")

    def _one(self, destination: tuple[str, int]) -> None:
        cfg = self.config
        assert self.encoder is not None
        started = time.perf_counter()
        snap = self.server.snapshot()
        with self.server.world_lock:
            image = self.renderer.render(
                self.mount, np.asarray(snap.position), np.asarray(snap.quaternion)
            )
        encoding = time.perf_counter()
        if image.shape[:2] != (cfg.height, cfg.width):
            import cv2

            image = cv2.resize(image, (cfg.width, cfg.height), interpolation=cv2.INTER_LINEAR)
        access_unit = self.encoder.encode(image)
        for datagram in packetise(access_unit, cfg.packet_bytes):
            try:
                self.sock.sendto(datagram, destination)
                self.datagrams += 1
            except OSError:
                self.send_errors += 1
        done = time.perf_counter()
        self.frames += 1
        self._run_frames += 1
        self.encode_s += done - started
        self.latency_s.append(done - encoding)
        if len(self.latency_s) > 300:
            del self.latency_s[:-300]

    def close(self) -> None:
        """Stop the thread and close the socket."""
        self.stop_event.set()
        if self.is_alive():
            self.join(5.0)
        if self.encoder is not None:
            self.encoder.close()
        with contextlib.suppress(OSError):
            self.sock.close()
