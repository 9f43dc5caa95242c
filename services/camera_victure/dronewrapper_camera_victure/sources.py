"""Camera sources: what a ``source`` string names, and the V4L2 mode handling over OpenCV.

Pure helpers (no device needed): :func:`classify_source`, :func:`request_mode` and
:func:`probe_modes` drive any object with OpenCV's ``VideoCapture`` interface (``set``, ``get``,
``isOpened``, ``read``, ``release``), so the tests run them against a fake capture; the V4L2
device itself is reached only through OpenCV (``cv2.CAP_V4L2``).
"""

from __future__ import annotations

import glob
import os
import re
from dataclasses import dataclass
from pathlib import Path
from typing import Any

SOURCE_KINDS = ("device", "file", "url", "pattern")
URL_SCHEMES = ("rtsp", "rtsps", "rtmp", "http", "https", "udp", "rtp", "srt", "tcp")

# cv2 property ids, spelled here so this module does not import OpenCV (values from cv2)
CAP_PROP_POS_MSEC = 0
CAP_PROP_FRAME_WIDTH = 3
CAP_PROP_FRAME_HEIGHT = 4
CAP_PROP_FPS = 5
CAP_PROP_FOURCC = 6
CAP_PROP_FRAME_COUNT = 7

COMMON_MODES = ((320, 240), (640, 480), (800, 600), (1280, 720), (1920, 1080))
"""Sizes :func:`probe_modes` asks a device for when listing it (px)."""


class SourceError(Exception):
    """The source cannot be used at all (missing or busy device, unsupported mode, missing
    file): an error at start-up, exit status 2. The message names the source."""


class SourceUnavailable(Exception):
    """The source is not reachable now (a stream not up yet, a device unplugged): retried."""


def classify_source(source: str, kind: str = "auto") -> str:
    """The kind of ``source``: ``device``, ``file``, ``url`` or ``pattern``.

    ``auto``: ``pattern`` is the test pattern, a bare index or ``/dev/video*`` a device,
    ``scheme://...`` a URL (the scheme must be one FFmpeg streams from), anything else a file.

    Raises:
        ValueError: a URL with a scheme that is not a network stream (``ftp://``, ``htp://``).
    """
    if kind != "auto":
        return kind
    text = source.strip()
    if text == "pattern":
        return "pattern"
    if text.isdigit() or text.startswith("/dev/video"):
        return "device"
    match = re.match(r"([A-Za-z][A-Za-z0-9+.-]*)://", text)
    if match:
        scheme = match.group(1).lower()
        if scheme == "file":
            return "file"
        if scheme not in URL_SCHEMES:
            raise ValueError(
                f"source {source!r}: unsupported URL scheme {scheme!r} "
                f"(streams: {', '.join(URL_SCHEMES)})"
            )
        return "url"
    return "file"


def device_path(source: str) -> str:
    """``/dev/videoN`` for an index ``N``, the path itself otherwise."""
    return f"/dev/video{int(source)}" if source.strip().isdigit() else source.strip()


def list_device_paths() -> list[str]:
    """The V4L2 capture nodes present, ``/dev/video0`` first."""
    return sorted(glob.glob("/dev/video*"), key=lambda p: (len(p), p))


def check_device_present(path: str) -> None:
    """Raises :class:`SourceError` naming ``path`` and the devices found when it is missing,
    or when this user may not open it."""
    if not os.path.exists(path):
        found = ", ".join(list_device_paths()) or "none"
        raise SourceError(f"no camera device {path} (devices found: {found})")
    if not os.access(path, os.R_OK | os.W_OK):
        raise SourceError(f"no permission to open {path} (add the user to the 'video' group)")


def check_file_present(path: str) -> Path:
    """The file as a Path; raises :class:`SourceError` when it is missing or not a file."""
    file = Path(path[len("file://") :] if path.startswith("file://") else path)
    if not file.is_file():
        raise SourceError(f"no video file {file}")
    return file


def fourcc_text(code: float) -> str:
    """``'MJPG'`` for the numeric FOURCC OpenCV reports ("" when 0 / unknown)."""
    value = int(code)
    if value <= 0:
        return ""
    return "".join(chr((value >> (8 * i)) & 0xFF) for i in range(4)).strip("\x00 ")


def fourcc_code(text: str) -> int:
    """The numeric FOURCC of ``'MJPG'`` (as ``cv2.VideoWriter_fourcc``)."""
    padded = (text + "    ")[:4]
    return sum(ord(c) << (8 * i) for i, c in enumerate(padded))


@dataclass(frozen=True)
class Mode:
    """A capture mode: size (px), frame rate (Hz, 0 = unknown), pixel format ("" = unknown)."""

    width: int
    height: int
    fps: float
    pixel_format: str

    def __str__(self) -> str:
        fmt = f" {self.pixel_format}" if self.pixel_format else ""
        return f"{self.width}x{self.height}{fmt} @{self.fps:g} fps"


def granted_mode(cap: Any) -> Mode:
    """The mode ``cap`` reports now."""
    return Mode(
        int(cap.get(CAP_PROP_FRAME_WIDTH)),
        int(cap.get(CAP_PROP_FRAME_HEIGHT)),
        float(cap.get(CAP_PROP_FPS)),
        fourcc_text(cap.get(CAP_PROP_FOURCC)),
    )


def request_mode(cap: Any, width: int, height: int, fps: float, pixel_format: str) -> Mode:
    """Ask ``cap`` for a mode and read back what it granted.

    The pixel format goes first (a V4L2 driver picks the sizes it offers per format), then
    the size, then the rate; 0 / "" leave that part at the device's default.
    """
    if pixel_format:
        cap.set(CAP_PROP_FOURCC, fourcc_code(pixel_format))
    if width > 0 and height > 0:
        cap.set(CAP_PROP_FRAME_WIDTH, width)
        cap.set(CAP_PROP_FRAME_HEIGHT, height)
    if fps > 0:
        cap.set(CAP_PROP_FPS, fps)
    return granted_mode(cap)


def mode_mismatches(requested: Mode, granted: Mode) -> list[str]:
    """What of ``requested`` the device did not grant (size, pixel format), for an error.

    A frame rate that differs is not a mismatch here (drivers round it; it is reported).
    """
    out = []
    if requested.width > 0 and (granted.width, granted.height) != (
        requested.width,
        requested.height,
    ):
        out.append(
            f"size {requested.width}x{requested.height} (got {granted.width}x{granted.height})"
        )
    if requested.pixel_format and granted.pixel_format != requested.pixel_format:
        out.append(
            f"pixel format {requested.pixel_format} (got {granted.pixel_format or 'unknown'})"
        )
    return out


def probe_modes(cap: Any, formats: tuple[str, ...] = ("MJPG", "YUYV")) -> list[Mode]:
    """The distinct modes ``cap`` grants when asked for each common size in each format.

    What ``--list`` shows: OpenCV has no mode enumeration, so the device is asked and its
    answers read back (each distinct granted mode once, sorted by format then size).
    """
    found: set[Mode] = set()
    for pixel_format in formats:
        for width, height in COMMON_MODES:
            mode = request_mode(cap, width, height, 0, pixel_format)
            if mode.width > 0 and mode.pixel_format == pixel_format:
                found.add(mode)
    return sorted(found, key=lambda m: (m.pixel_format, m.width * m.height, m.fps))


def driver_stamp(pos_msec: float, wall_now: float, mono_now: float, max_age: float = 1.0):
    """The wall-clock capture time of a V4L2 frame from its driver timestamp, or None.

    OpenCV's V4L2 backend reports the buffer's timestamp (``CAP_PROP_POS_MSEC``, ms on the
    monotonic clock). It is converted to the epoch through the current offset between the
    clocks; a value that is not a plausible recent monotonic time (0, in the future, older than
    ``max_age`` s) is not a driver stamp and gives None (the caller stamps the read time).
    """
    if not pos_msec > 0:
        return None
    age = mono_now - pos_msec / 1000.0
    if not 0.0 <= age <= max_age:
        return None
    return wall_now - age
