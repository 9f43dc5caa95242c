"""A plain OpenCV camera publisher: a USB camera (or a video file) on ``{ns}/{camera}/image_raw``.

A stop-gap for the real-hardware graph until the camera_victure service exists: it opens
``cv2.VideoCapture(device)`` (an index like ``0``, a ``/dev/videoN`` path, or a file / URL),
stamps each frame with the wall-clock time right after capture, and publishes it as a ``bgr8``
Image (and, with ``compressed: true``, a JPEG CompressedImage for Wi-Fi links). It announces
readiness after the first frame. A video file loops (``loop: true``) or ends the process.

    python -m dronewrapper_compose.usb_camera --set device=/dev/video0 --connect tcp/127.0.0.1:7447
"""

from __future__ import annotations

import logging
import time

import msgspec

from dronewrapper.msgs import registry
from dronewrapper.msgs.sensor import CompressedImage, Image
from dronewrapper.msgs.std import Header
from dronewrapper.runtime import Node, Ratekeeper
from dronewrapper.runtime.service import run_service

log = logging.getLogger("usb_camera")


class Config(msgspec.Struct, kw_only=True, forbid_unknown_fields=True):
    """Camera config.

    Attributes:
        device: camera index (``"0"``), device path (``/dev/video0``) or video file / URL.
        camera: camera name in the key (``cam_frontal``).
        width, height: requested capture size (px; 0 = the camera's default).
        fps: publish rate (Hz); also requested from the camera.
        compressed: also publish JPEG on ``image_raw/compressed``.
        jpeg_quality: JPEG quality 1..100.
        loop: restart a video file at its end (a camera never ends).
        open_timeout: give up when no frame comes within this many seconds (s).
    """

    device: str = "0"
    camera: str = "cam_frontal"
    width: int = 640
    height: int = 480
    fps: float = 30.0
    compressed: bool = False
    jpeg_quality: int = 80
    loop: bool = True
    open_timeout: float = 10.0


def _open(cv2, config: Config):
    source: int | str = int(config.device) if config.device.isdigit() else config.device
    cap = cv2.VideoCapture(source)
    if config.width > 0 and config.height > 0:
        cap.set(cv2.CAP_PROP_FRAME_WIDTH, config.width)
        cap.set(cv2.CAP_PROP_FRAME_HEIGHT, config.height)
    cap.set(cv2.CAP_PROP_FPS, config.fps)
    return cap


def run(node: Node, config: Config) -> int:
    """Capture and publish until stopped (see the module doc)."""
    import cv2

    if not config.fps > 0:
        log.error("fps must be > 0, got %s", config.fps)
        return 2
    cap = _open(cv2, config)
    raw = node.publisher(registry.IMAGE_RAW, camera=config.camera)
    jpeg = node.publisher(registry.IMAGE_COMPRESSED, camera=config.camera)
    rate = Ratekeeper(config.fps, stop=node.stop_event)
    last_frame_at = time.monotonic()
    seq = 0
    try:
        while rate.sleep():
            ok, frame = cap.read()
            stamp = time.time()
            if not ok or frame is None:
                if cap.get(cv2.CAP_PROP_FRAME_COUNT) > 0:  # a video file ended
                    if not config.loop:
                        log.info("end of %s", config.device)
                        return 0
                    cap.set(cv2.CAP_PROP_POS_FRAMES, 0)
                if time.monotonic() - last_frame_at > config.open_timeout:
                    log.error("no frame from %s for %.0f s", config.device, config.open_timeout)
                    return 1
                continue
            last_frame_at = time.monotonic()
            header = Header(stamp=stamp, frame_id=config.camera, seq=seq)
            if frame.ndim == 2:
                frame = cv2.cvtColor(frame, cv2.COLOR_GRAY2BGR)
            h, w = frame.shape[:2]
            raw.put(Image(header=header, height=h, width=w, step=w * 3, data=frame.tobytes()))
            if config.compressed:
                ok, buf = cv2.imencode(
                    ".jpg", frame, [cv2.IMWRITE_JPEG_QUALITY, config.jpeg_quality]
                )
                if ok:
                    jpeg.put(CompressedImage(header=header, format="jpeg", data=buf.tobytes()))
            if seq == 0:
                log.info("publishing %dx%d frames from %s", w, h, config.device)
                node.announce()
            seq += 1
    finally:
        cap.release()
    return 0


if __name__ == "__main__":
    raise SystemExit(run_service("usb_camera", __doc__, Config, run))
