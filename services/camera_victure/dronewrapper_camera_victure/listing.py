"""``--list``: the V4L2 devices found and the modes each grants, through OpenCV."""

from __future__ import annotations

from dronewrapper_camera_victure.capture import Factory, opencv_factory
from dronewrapper_camera_victure.sources import granted_mode, list_device_paths, probe_modes


def describe_devices(paths: list[str], factory: Factory = opencv_factory) -> list[str]:
    """One block of lines per device: its path, default mode, then the modes it grants."""
    import cv2

    lines: list[str] = []
    for path in paths:
        cap = factory(path, cv2.CAP_V4L2, [])
        try:
            if not cap.isOpened():
                lines.append(f"{path}: cannot open (busy, or not a capture node)")
                continue
            lines.append(f"{path}: default {granted_mode(cap)}")
            modes = probe_modes(cap)
            lines.extend(f"  {mode}" for mode in modes)
            if not modes:
                lines.append("  (no MJPG/YUYV mode answered)")
        finally:
            cap.release()
    return lines


def list_devices() -> int:
    """Print the devices and their modes; exit status 0 (1 when there is none)."""
    paths = list_device_paths()
    if not paths:
        print("no V4L2 devices (/dev/video*) found")
        return 1
    for line in describe_devices(paths):
        print(line)
    return 0
