"""Which person a detection is, from the simulator's ground truth: each person's box as the
camera sees them, and the best-overlapping person of a detected box (pure).

Boxes are (left, top, right, bottom) in image px (origin top-left, y down). A person's box is
their projected feet-to-head segment, 0.4 of its height wide.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from dronewrapper_sim.render.camera import FRONTAL, PinholeCamera, project

Box = tuple[float, float, float, float]

MIN_IOU = 0.3
"""A detection belongs to nobody below this overlap with every person."""
NEARER_WITHIN = 0.1
"""Overlaps this close to the best one are a tie, won by the nearer person."""


def iou(a: tuple[float, ...], b: tuple[float, ...]) -> float:
    """Intersection over union of two boxes (0..1; 0 when neither has an area)."""
    ix = max(0.0, min(a[2], b[2]) - max(a[0], b[0]))
    iy = max(0.0, min(a[3], b[3]) - max(a[1], b[1]))
    inter = ix * iy
    union = (a[2] - a[0]) * (a[3] - a[1]) + (b[2] - b[0]) * (b[3] - b[1]) - inter
    return inter / union if union > 0 else 0.0


def person_boxes(
    world: Any, camera: PinholeCamera, vehicle: np.ndarray, quat: np.ndarray
) -> dict[str, tuple[Box, float]]:
    """Each person in the frontal camera's view from ``vehicle`` (ENU m) at attitude ``quat``
    (x y z w): name -> (box px, depth m)."""
    out = {}
    for obj in world.objects:
        if obj.kind != "person":
            continue
        px, depth = project(np.array([obj.position, obj.top_enu]), vehicle, quat, FRONTAL, camera)
        if not np.all(np.isfinite(px)):
            continue
        height = px[0, 1] - px[1, 1]
        cx = (px[0, 0] + px[1, 0]) / 2
        out[obj.name] = ((cx - 0.2 * height, px[1, 1], cx + 0.2 * height, px[0, 1]), depth[0])
    return out


def owner(box: tuple[float, ...], people: dict[str, tuple[Box, float]]) -> str | None:
    """The person a detected box belongs to: the best overlap above :data:`MIN_IOU`, the
    nearer of those within :data:`NEARER_WITHIN` of it; None when nobody overlaps enough."""
    scored = [(iou(box, pbox), -depth, name) for name, (pbox, depth) in people.items()]
    scored = [s for s in scored if s[0] > MIN_IOU]
    if not scored:
        return None
    best = max(s[0] for s in scored)
    return max((s for s in scored if s[0] >= best - NEARER_WITHIN), key=lambda s: s[1])[2]
