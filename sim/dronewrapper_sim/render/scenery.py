"""Distant scenery: a few hundred trees scattered in clumps 45-110 m around the origin.

They give the horizon a skyline and the frontal camera a heading and parallax cue. Trees are
drawn into the background at its working resolution, far to near, hazed like the ground
(aerial perspective), as a trunk and a crown (round deciduous or conical conifer). Greens and
greyish browns only, so nothing looks like the red beacon.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import cv2
import numpy as np

from dronewrapper_sim.render.camera import CameraPose

__all__ = ["Trees", "draw_trees", "make_trees"]

_SHIFT = 3
_ONE = 1 << _SHIFT
_CROWN_BGR = np.array(
    [[40.0, 95.0, 55.0], [35.0, 80.0, 45.0], [50.0, 105.0, 70.0], [45.0, 75.0, 40.0]]
)
_TRUNK_BGR = np.array([55.0, 62.0, 72.0])


@dataclass(frozen=True)
class Trees:
    """Tree positions (ENU m, on the ground), heights (m), crown radii (m), kinds, colours."""

    xy: np.ndarray  # N x 2
    height: np.ndarray  # N
    crown: np.ndarray  # N
    conifer: np.ndarray  # N bool
    color: np.ndarray  # N x 3 BGR


def make_trees(seed: int = 0, clumps: int = 18, inner_m: float = 45.0, outer_m: float = 110.0):
    """Trees in ``clumps`` clumps between ``inner_m`` and ``outer_m`` from the origin."""
    rng = np.random.default_rng([seed, 7])
    xy, height, crown, conifer, color = [], [], [], [], []
    for _ in range(clumps):
        r = rng.uniform(inner_m + 8.0, outer_m - 8.0)
        a = rng.uniform(0.0, 2.0 * math.pi)
        centre = np.array([r * math.cos(a), r * math.sin(a)])
        kind = rng.uniform() < 0.4
        for _ in range(int(rng.integers(3, 14))):
            p = centre + rng.normal(0.0, 6.0, 2)
            if not inner_m <= np.hypot(*p) <= outer_m:
                continue
            h = rng.uniform(6.0, 14.0)
            xy.append(p)
            height.append(h)
            crown.append(h * rng.uniform(0.22, 0.32))
            conifer.append(kind if rng.uniform() < 0.85 else not kind)
            color.append(_CROWN_BGR[int(rng.integers(len(_CROWN_BGR)))] * rng.uniform(0.85, 1.1))
    return Trees(
        np.array(xy), np.array(height), np.array(crown), np.array(conifer), np.array(color)
    )


def draw_trees(
    image: np.ndarray,
    trees: Trees,
    pose: CameraPose,
    matrix: np.ndarray,
    haze_bgr: np.ndarray,
    fog_distance_m: float,
) -> None:
    """Draw ``trees`` into ``image`` seen from ``pose`` with intrinsics ``matrix`` (3 x 3)."""
    if len(trees.xy) == 0:
        return
    h_img, w_img = image.shape[:2]
    base = np.column_stack((trees.xy, np.zeros(len(trees.xy))))
    top = base.copy()
    top[:, 2] = trees.height
    cam_base = pose.to_camera(base)
    cam_top = pose.to_camera(top)
    depth = np.minimum(cam_base[:, 2], cam_top[:, 2])
    fx, cx, cy = matrix[0, 0], matrix[0, 2], matrix[1, 2]
    ok = depth > 1.0
    if not np.any(ok):
        return
    ub = fx * cam_base[:, 0] / np.maximum(cam_base[:, 2], 1e-6) + cx
    vb = fx * cam_base[:, 1] / np.maximum(cam_base[:, 2], 1e-6) + cy
    ut = fx * cam_top[:, 0] / np.maximum(cam_top[:, 2], 1e-6) + cx
    vt = fx * cam_top[:, 1] / np.maximum(cam_top[:, 2], 1e-6) + cy
    crown_px = fx * trees.crown / np.maximum(depth, 1e-6)
    margin = crown_px + 2.0
    ok &= (np.maximum(ub, ut) + margin >= 0) & (np.minimum(ub, ut) - margin < w_img)
    ok &= (np.maximum(vb, vt) + margin >= 0) & (np.minimum(vb, vt) - margin < h_img)
    dist = np.hypot(trees.xy[:, 0] - pose.position_enu[0], trees.xy[:, 1] - pose.position_enu[1])
    fog = (1.0 - np.exp(-dist / fog_distance_m))[:, None]
    crowns = (trees.color * (1.0 - fog) + haze_bgr * fog).tolist()
    shades = (trees.color * (0.85 * (1.0 - fog)) + haze_bgr * fog).tolist()
    trunks = (_TRUNK_BGR * (1.0 - fog) + haze_bgr * fog).tolist()
    order = np.nonzero(ok)[0]
    order = order[np.argsort(-depth[order], kind="stable")].tolist()
    ub, vb, ut, vt, crown_px = ub.tolist(), vb.tolist(), ut.tolist(), vt.tolist(), crown_px.tolist()
    conifer = trees.conifer.tolist()
    for i in order:
        r = crown_px[i]
        bu, bv, tu, tv = ub[i], vb[i], ut[i], vt[i]
        au, av = tu - bu, tv - bv  # trunk axis in the image
        length = math.hypot(au, av) or 1.0
        trunk_px = max(1, round(0.12 * r))
        if conifer[i]:
            su, sv = bu + 0.15 * au, bv + 0.15 * av
            nu, nv = -av / length * r, au / length * r
            cv2.line(image, _fix(bu, bv), _fix(su, sv), trunks[i], trunk_px, cv2.LINE_8, _SHIFT)
            tri = np.array([_fix(su + nu, sv + nv), _fix(su - nu, sv - nv), _fix(tu, tv)], np.int32)
            cv2.fillConvexPoly(image, tri, shades[i], cv2.LINE_8, _SHIFT)
        else:
            cu, cv_ = bu + au * 0.72, bv + av * 0.72
            cv2.line(image, _fix(bu, bv), _fix(cu, cv_), trunks[i], trunk_px, cv2.LINE_8, _SHIFT)
            _ball(image, cu + 0.3 * r, cv_ + 0.1 * r, r * 0.75, shades[i])
            _ball(image, cu - 0.2 * r, cv_ - 0.15 * r, r * 0.85, crowns[i])


def _ball(image: np.ndarray, u: float, v: float, radius: float, color) -> None:
    cv2.circle(image, _fix(u, v), max(1, round(radius * _ONE)), color, -1, cv2.LINE_8, _SHIFT)


def _fix(u: float, v: float) -> tuple[int, int]:
    return (round(u * _ONE), round(v * _ONE))
