"""Procedural people: an articulated body (head, torso, arms, legs) walking, drawn in 3-D.

The skeleton is built in the person's own frame (x forward, y left, z up, origin on the ground
between the feet) from the height and the gait phase, turned into ENU by the person's position
and yaw, and every point is projected through the real camera. Limbs are shaded capsules, the
torso and pelvis shaded convex hulls of elliptical cross-sections, the head two spheres (hair
and face); parts are drawn far to near, so views from the front, the side, behind or above all
look right. Proportions are fractions of the height (an adult is about 7.5 heads tall).
"""

from __future__ import annotations

import math
from functools import lru_cache
from typing import Any

import cv2
import numpy as np

from dronewrapper_sim.render.camera import (
    NEAR_PLANE_M,
    CameraPose,
    PinholeCamera,
    project_camera_points,
)
from dronewrapper_sim.world.looks import PersonLook

__all__ = ["JOINTS", "draw_person", "hull_points", "skeleton"]

JOINTS: tuple[str, ...] = (
    "hip_l", "knee_l", "ankle_l", "toe_l", "shoulder_l", "elbow_l", "wrist_l", "hand_l",
    "hip_r", "knee_r", "ankle_r", "toe_r", "shoulder_r", "elbow_r", "wrist_r", "hand_r",
    "neck_base", "neck_top", "hair", "face", "hair_end", "heel_l", "heel_r",
)  # fmt: skip
"""Names of the rows of :func:`skeleton`'s array."""
_J = {name: i for i, name in enumerate(JOINTS)}

_SHIFT = 4
_ONE = 1 << _SHIFT
_LIGHT_U, _LIGHT_V = -0.45 / math.hypot(0.45, 0.9), -0.9 / math.hypot(0.45, 0.9)  # toward light
_RIM = 0.68  # brightness of the shadowed rim of every part

# (height, half width, half depth) of the torso's cross-sections, as fractions of the height
_SHIRT_RINGS = (
    (0.845, 0.055, 0.040),  # collar
    (0.825, 0.105, 0.055),  # sloping shoulder tops
    (0.795, 0.120, 0.062),  # shoulders
    (0.72, 0.112, 0.080),  # chest
    (0.60, 0.098, 0.070),  # waist
    (0.53, 0.102, 0.072),  # hips (shirt hem)
)
_PELVIS_RINGS = ((0.55, 0.100, 0.066), (0.46, 0.095, 0.070))
_RING_ANGLES = np.linspace(0.0, 2.0 * math.pi, 10, endpoint=False)

# (kind, joints, radius as a fraction of the height, colour) of every capsule and sphere
_LIMBS: tuple[tuple[str, tuple[str, ...], float, str], ...] = (
    ("capsule", ("neck_base", "neck_top"), 0.03, "skin"),
    ("sphere", ("hair",), 0.058, "hair"),
    ("sphere", ("face",), 0.055, "skin"),
    ("capsule", ("hair", "hair_end"), 0.024, "long_hair"),
    *(
        part
        for s in ("l", "r")
        for part in (
            ("capsule", (f"hip_{s}", f"knee_{s}"), 0.05, "pants"),
            ("capsule", (f"knee_{s}", f"ankle_{s}"), 0.036, "shins"),
            ("capsule", (f"heel_{s}", f"toe_{s}"), 0.028, "shoes"),
            ("capsule", (f"shoulder_{s}", f"elbow_{s}"), 0.034, "shirt"),
            ("capsule", (f"elbow_{s}", f"wrist_{s}"), 0.028, "sleeve"),
            ("sphere", (f"hand_{s}",), 0.03, "skin"),
        )
    ),
)
_FACE = (_J["face"],)
_LIMB_INDEX = tuple(tuple(_J[n] for n in joints) for _, joints, _, _ in _LIMBS)


def skeleton(height_m: float, phase_rad: float, gait: float) -> np.ndarray:
    """Joint positions (len(JOINTS) x 3, m) in the person frame (x forward, y left, z up).

    Args:
        height_m: standing height, m.
        phase_rad: walking phase (a full cycle is two steps; the legs are half a cycle apart).
        gait: 0 standing still .. 1 full stride (swings scale with it).
    """
    h = height_m
    g = min(1.0, max(0.0, gait))
    thigh, shin, foot = 0.245 * h, 0.245 * h, 0.13 * h
    upper_arm, forearm = 0.175 * h, 0.15 * h
    hip_z, shoulder_z = 0.52 * h, 0.81 * h
    spread_c, spread_s = math.cos(0.09), math.sin(0.09)  # arms slightly away from the body
    rows: list[tuple[float, float, float]] = []
    heels: list[tuple[float, float, float]] = []
    for sign, offset in ((1.0, 0.0), (-1.0, math.pi)):
        phi = phase_rad + offset
        swing = 0.45 * g * math.sin(phi)  # thigh angle from vertical, forward +
        knee_bend = 0.06 + g * 0.75 * max(0.0, math.cos(phi)) ** 1.5
        hy = sign * 0.055 * h
        kx, kz = thigh * math.sin(swing), hip_z - thigh * math.cos(swing)
        a = swing - knee_bend
        ax, az = kx + shin * math.sin(a), kz - shin * math.cos(a)
        arm = -0.75 * swing
        sy = sign * 0.115 * h
        ex = upper_arm * math.sin(arm) * spread_c
        ey = sy + sign * upper_arm * spread_s
        ez = shoulder_z - upper_arm * math.cos(arm)
        b = arm + 0.2 + 0.35 * g
        dx, dy, dz = math.sin(b) * spread_c, sign * spread_s, -math.cos(b)
        wx, wy, wz = ex + forearm * dx, ey + forearm * dy, ez + forearm * dz
        hand = 0.045 * h
        rows += [
            (0.0, hy, hip_z),
            (kx, hy, kz),
            (ax, hy, az),
            (ax + 0.8 * foot, hy, az - 0.025 * h),
            (0.0, sy, shoulder_z),
            (ex, ey, ez),
            (wx, wy, wz),
            (wx + hand * dx, wy + hand * dy, wz + hand * dz),
        ]
        heels.append((ax - 0.2 * foot, hy, az - 0.025 * h))
    head_z = 0.93 * h
    rows += [
        (0.0, 0.0, 0.82 * h),  # neck base
        (0.004 * h, 0.0, 0.875 * h),  # neck top
        (-0.008 * h, 0.0, head_z + 0.010 * h),  # hair (back and top of the head)
        (0.008 * h, 0.0, head_z - 0.008 * h),  # face
        (-0.052 * h, 0.0, head_z - 0.075 * h),  # end of a pony tail (behind the neck)
        *heels,
    ]
    joints = np.array(rows)
    # keep the lower foot on the ground (the body bobs as it walks)
    lowest = min(joints[_J["ankle_l"], 2], joints[_J["ankle_r"], 2])
    joints[:, 2] += 0.045 * h - lowest
    return joints


@lru_cache(maxsize=64)
def hull_points(height_m: float) -> tuple[np.ndarray, np.ndarray]:
    """Points (N x 3, person frame, standing) whose convex hulls are the shirt and the pelvis."""

    def rings(spec) -> np.ndarray:
        pts = [
            np.column_stack(
                (
                    d * height_m * np.cos(_RING_ANGLES),
                    w * height_m * np.sin(_RING_ANGLES),
                    np.full(_RING_ANGLES.size, z * height_m),
                )
            )
            for z, w, d in spec
        ]
        out = np.concatenate(pts)
        out.setflags(write=False)
        return out

    return rings(_SHIRT_RINGS), rings(_PELVIS_RINGS)


def _shade(color: tuple[int, int, int], factor: float) -> tuple[float, float, float]:
    return (
        min(255.0, color[0] * factor),
        min(255.0, color[1] * factor),
        min(255.0, color[2] * factor),
    )


def draw_person(
    image: np.ndarray,
    pose: CameraPose,
    camera: PinholeCamera,
    position_enu: np.ndarray,
    yaw_rad: float,
    height_m: float,
    phase_rad: float,
    gait: float,
    look: PersonLook,
) -> None:
    """Draw a person standing at ``position_enu`` (base on the ground) facing ``yaw_rad``."""
    h = height_m
    joints = skeleton(h, phase_rad, gait)
    lift = float(joints[_J["neck_base"], 2] - 0.82 * h)
    shirt, pelvis = hull_points(h)
    n_j, n_s = len(joints), len(shirt)
    local = np.concatenate((joints, shirt, pelvis))
    local[n_j:, 2] += lift
    c, s = math.cos(yaw_rad), math.sin(yaw_rad)
    rot = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
    cam_pts = pose.to_camera(local @ rot.T + np.asarray(position_enu, dtype=float))
    pixels, depth = project_camera_points(cam_pts, camera)
    px = pixels.tolist()
    d = depth.tolist()
    f = camera.fx
    colors = {
        "skin": look.skin_bgr,
        "hair": look.hair_bgr,
        "pants": look.pants_bgr,
        "shoes": look.shoes_bgr,
        "shirt": look.shirt_bgr,
        "sleeve": look.shirt_bgr if look.long_sleeves else look.skin_bgr,
        "shins": look.skin_bgr if look.shorts else look.pants_bgr,
        "long_hair": look.hair_bgr if look.long_hair else None,
    }
    # depth, order, kind, points (pixel list or array), radius px, BGR
    drawn: list[tuple[float, int, str, Any, float, tuple[int, int, int]]] = []
    for k, ((kind, _, radius, part), idx) in enumerate(zip(_LIMBS, _LIMB_INDEX, strict=True)):
        bgr = colors[part]
        if bgr is None:
            continue
        ds = [d[i] for i in idx]
        r_m = radius * h
        if min(ds) < NEAR_PLANE_M + r_m:
            continue
        mean = sum(ds) / len(ds)
        if idx == _FACE:  # the face is in front of the hair when seen from the side
            mean -= 0.01 * h
        drawn.append((mean, k, kind, [px[i] for i in idx], f * r_m / mean, bgr))
    for k, (start, stop, part, bias) in enumerate(
        ((n_j, n_j + n_s, "shirt", 0.04), (n_j + n_s, len(d), "pants", 0.045))
    ):
        part_depth = depth[start:stop]
        if part_depth.min() < NEAR_PLANE_M:
            continue
        mean = float(part_depth.mean()) + bias * h
        bgr = colors[part]
        assert bgr is not None  # shirt and pants are always drawn
        drawn.append((mean, 100 + k, "hull", pixels[start:stop], 0.0, bgr))
    drawn.sort(key=lambda item: (-item[0], item[1]))
    for _, _, kind, pts, radius_px, color in drawn:
        if kind == "hull":
            _draw_hull(image, pts, color)
        elif kind == "sphere":
            _draw_ball(image, pts[0], radius_px, color)
        else:
            _draw_capsule(image, pts[0], pts[1], radius_px, color)


def _fix(u: float, v: float) -> tuple[int, int]:
    return (round(u * _ONE), round(v * _ONE))


def _draw_capsule(image, p0, p1, radius_px: float, color) -> None:
    thick = max(1, round(2.0 * radius_px))
    a, b = _fix(p0[0], p0[1]), _fix(p1[0], p1[1])
    cv2.line(image, a, b, _shade(color, _RIM), thick, cv2.LINE_AA, _SHIFT)
    if radius_px >= 1.5:
        ou, ov = _LIGHT_U * radius_px * 0.22, _LIGHT_V * radius_px * 0.22
        a, b = _fix(p0[0] + ou, p0[1] + ov), _fix(p1[0] + ou, p1[1] + ov)
        inner = max(1, round(2.0 * radius_px * 0.55))
        cv2.line(image, a, b, _shade(color, 1.0), inner, cv2.LINE_AA, _SHIFT)


def _draw_ball(image, p, radius_px: float, color) -> None:
    centre = _fix(p[0], p[1])
    cv2.circle(
        image, centre, max(1, round(radius_px * _ONE)), _shade(color, _RIM), -1, cv2.LINE_AA, _SHIFT
    )
    if radius_px >= 1.5:
        q = _fix(p[0] + _LIGHT_U * radius_px * 0.25, p[1] + _LIGHT_V * radius_px * 0.25)
        cv2.circle(
            image, q, round(radius_px * 0.62 * _ONE), _shade(color, 1.0), -1, cv2.LINE_AA, _SHIFT
        )


def _draw_hull(image, pts: np.ndarray, color) -> None:
    hull = cv2.convexHull(np.round(pts * _ONE).astype(np.int32))
    cv2.fillConvexPoly(image, hull, _shade(color, _RIM), cv2.LINE_AA, _SHIFT)
    centre = pts.mean(axis=0)
    size = float(np.ptp(pts[:, 0]) + np.ptp(pts[:, 1])) / 2.0
    inner = (pts - centre) * 0.72 + centre + np.array([_LIGHT_U, _LIGHT_V]) * size * 0.08
    hull2 = cv2.convexHull(np.round(inner * _ONE).astype(np.int32))
    cv2.fillConvexPoly(image, hull2, _shade(color, 1.0), cv2.LINE_AA, _SHIFT)
