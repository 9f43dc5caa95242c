"""Soft blob shadows on the ground under objects (they show where a flying beacon is)."""

from __future__ import annotations

import math

import cv2
import numpy as np

from dronewrapper_sim.render.camera import NEAR_PLANE_M, CameraPose, PinholeCamera

__all__ = ["draw_shadow"]

_SEGMENTS = 16
_CIRCLE = np.array(
    [(math.cos(a), math.sin(a)) for a in np.linspace(0.0, 2.0 * math.pi, _SEGMENTS, endpoint=False)]
)


def draw_shadow(image: np.ndarray, pose: CameraPose, camera: PinholeCamera, obj) -> None:
    """Darken an ellipse on the ground under ``obj`` (a WorldObject), fainter the higher it is."""
    if obj.kind == "person":
        radius, strength = 0.3 * obj.height_m / 1.75, 0.45
    else:
        height = max(0.0, float(obj.position[2]) - obj.radius_m)
        radius = obj.radius_m * (1.0 + 0.15 * height)
        strength = 0.45 / (1.0 + 0.35 * height)
    ring = np.zeros((_SEGMENTS, 3))
    ring[:, 0] = obj.position[0] + radius * _CIRCLE[:, 0]
    ring[:, 1] = obj.position[1] + radius * _CIRCLE[:, 1]
    cam = pose.to_camera(ring)
    if np.any(cam[:, 2] < NEAR_PLANE_M):
        return
    u = camera.fx * cam[:, 0] / cam[:, 2] + camera.cx
    v = camera.fy * cam[:, 1] / cam[:, 2] + camera.cy
    h, w = image.shape[:2]
    span = float(min(np.ptp(u), np.ptp(v)))
    sigma = max(0.7, 0.12 * span)
    pad = math.ceil(2.5 * sigma) + 1
    x0, x1 = max(0, math.floor(u.min()) - pad), min(w, math.ceil(u.max()) + pad + 1)
    y0, y1 = max(0, math.floor(v.min()) - pad), min(h, math.ceil(v.max()) + pad + 1)
    if x1 <= x0 or y1 <= y0 or (x1 - x0) * (y1 - y0) > w * h:
        return
    mask = np.zeros((y1 - y0, x1 - x0), np.float32)
    pts = np.round(np.stack((u - x0, v - y0), axis=1) * 16).astype(np.int32)
    cv2.fillConvexPoly(mask, pts, 1.0, cv2.LINE_AA, 4)
    mask = cv2.GaussianBlur(mask, (0, 0), sigma, borderType=cv2.BORDER_CONSTANT)
    roi = image[y0:y1, x0:x1]
    factor = 1.0 - strength * mask
    roi[...] = (roi * factor[:, :, None]).astype(np.uint8)
