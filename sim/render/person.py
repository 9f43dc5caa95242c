"""Procedural people: an articulated body (head, torso, arms, legs) walking, drawn in 3-D.

The skeleton is built in the person's own frame (x forward, y left, z up, origin on the ground
between the feet) from the height and the gait phase, turned into ENU by the person's position
and yaw, and every joint is projected through the real camera. Limbs are shaded capsules, the
torso a shaded convex hull of a box, the head two spheres (hair and face); parts are drawn far to
near, so the view from the front, the side, behind or above all look right.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import cv2
import numpy as np

from dronewrapper_sim.render.camera import (
    NEAR_PLANE_M,
    CameraPose,
    PinholeCamera,
    project_camera_points,
)
from dronewrapper_sim.world.looks import PersonLook

__all__ = ["Part", "body_parts", "draw_person", "skeleton"]

_SHIFT = 4
_ONE = 1 << _SHIFT
_LIGHT_2D = np.array([-0.45, -0.9]) / math.hypot(0.45, 0.9)  # image direction toward the light
_RIM = 0.68  # brightness of the shadowed rim of every part


def skeleton(height_m: float, phase_rad: float, gait: float) -> dict[str, np.ndarray]:
    """Joint positions (m) in the person frame (x forward, y left, z up) for a gait phase.

    Args:
        height_m: standing height, m.
        phase_rad: walking phase (a full cycle is two steps).
        gait: 0 standing still .. 1 full stride.
    """
    h = height_m
    g = float(np.clip(gait, 0.0, 1.0))
    thigh, shin, foot = 0.245 * h, 0.245 * h, 0.13 * h
    upper_arm, forearm = 0.175 * h, 0.15 * h
    hip_z, shoulder_z = 0.52 * h, 0.81 * h
    j: dict[str, np.ndarray] = {}
    for side, sign, offset in (("l", 1.0, 0.0), ("r", -1.0, math.pi)):
        phi = phase_rad + offset
        swing = 0.45 * g * math.sin(phi)  # thigh angle from vertical, forward +
        knee_bend = 0.06 + g * 0.75 * max(0.0, math.cos(phi)) ** 1.5
        hip = np.array([0.0, sign * 0.055 * h, hip_z])
        knee = hip + thigh * np.array([math.sin(swing), 0.0, -math.cos(swing)])
        a = swing - knee_bend
        ankle = knee + shin * np.array([math.sin(a), 0.0, -math.cos(a)])
        toe = ankle + np.array([foot * 0.8, 0.0, -0.025 * h])
        j[f"hip_{side}"], j[f"knee_{side}"], j[f"ankle_{side}"], j[f"toe_{side}"] = (
            hip,
            knee,
            ankle,
            toe,
        )
        arm = -0.75 * swing
        spread = 0.09
        shoulder = np.array([0.0, sign * 0.115 * h, shoulder_z])
        d1 = np.array([math.sin(arm) * math.cos(spread), sign * math.sin(spread), -math.cos(arm)])
        elbow = shoulder + upper_arm * d1
        b = arm + 0.2 + 0.35 * g
        d2 = np.array([math.sin(b) * math.cos(spread), sign * math.sin(spread), -math.cos(b)])
        wrist = elbow + forearm * d2
        j[f"shoulder_{side}"], j[f"elbow_{side}"], j[f"wrist_{side}"] = shoulder, elbow, wrist
        j[f"hand_{side}"] = wrist + 0.045 * h * d2
    # keep the lower foot on the ground (the body bobs as it walks)
    lowest = min(j["ankle_l"][2], j["ankle_r"][2])
    lift = 0.045 * h - lowest
    for key in j:
        j[key] = j[key] + np.array([0.0, 0.0, lift])
    top = 0.83 * h + lift
    j["neck_base"] = np.array([0.0, 0.0, top - 0.01 * h])
    j["neck_top"] = np.array([0.0, 0.0, top + 0.05 * h])
    j["head"] = np.array([0.0, 0.0, h - 0.065 * h + lift])
    j["hair"] = j["head"] + np.array([-0.008 * h, 0.0, 0.010 * h])
    j["face"] = j["head"] + np.array([0.007 * h, 0.0, -0.006 * h])
    return j


def _ring(z: float, half_w: float, half_d: float, lift: float, n: int = 10) -> list:
    """Points of an elliptical cross-section of the body at height ``z`` (person frame)."""
    return [
        (half_d * math.cos(a), half_w * math.sin(a), z + lift)
        for a in np.linspace(0.0, 2.0 * math.pi, n, endpoint=False)
    ]


def _torso_hulls(h: float, lift: float) -> tuple[np.ndarray, np.ndarray]:
    """Points whose convex hulls are the shirt (chest to hips) and the pelvis, person frame."""
    shirt = (
        _ring(0.835 * h, 0.075 * h, 0.045 * h, lift)  # sloping shoulder tops
        + _ring(0.80 * h, 0.118 * h, 0.062 * h, lift)  # shoulders
        + _ring(0.72 * h, 0.112 * h, 0.072 * h, lift)  # chest
        + _ring(0.60 * h, 0.098 * h, 0.064 * h, lift)  # waist
        + _ring(0.53 * h, 0.102 * h, 0.066 * h, lift)  # hips (shirt hem)
    )
    pelvis = _ring(0.55 * h, 0.100 * h, 0.066 * h, lift) + _ring(
        0.46 * h, 0.095 * h, 0.07 * h, lift
    )
    return np.array(shirt), np.array(pelvis)


@dataclass(frozen=True)
class Part:
    """One drawable part: ``capsule`` (two points), ``sphere`` (one point) or ``hull`` (many)."""

    kind: str
    points: np.ndarray  # N x 3, person frame, m
    radius_m: float
    color_bgr: tuple[int, int, int]
    depth_bias_m: float = 0.0


def body_parts(height_m: float, phase_rad: float, gait: float, look: PersonLook) -> list[Part]:
    """Every part of a person (person frame), in no particular order."""
    h = height_m
    j = skeleton(h, phase_rad, gait)
    lift = j["neck_base"][2] - (0.83 * h - 0.01 * h)
    shirt, pelvis = _torso_hulls(h, lift)
    sleeve = look.shirt_bgr if look.long_sleeves else look.skin_bgr
    parts = [
        Part("hull", shirt, 0.0, look.shirt_bgr, 0.04 * h),
        Part("hull", pelvis, 0.0, look.pants_bgr, 0.045 * h),
        Part("capsule", np.array([j["neck_base"], j["neck_top"]]), 0.028 * h, look.skin_bgr),
        Part("sphere", j["hair"][None], 0.054 * h, look.hair_bgr),
        Part("sphere", j["face"][None], 0.051 * h, look.skin_bgr),
    ]
    for s in ("l", "r"):
        parts += [
            Part("capsule", np.array([j[f"hip_{s}"], j[f"knee_{s}"]]), 0.05 * h, look.pants_bgr),
            Part("capsule", np.array([j[f"knee_{s}"], j[f"ankle_{s}"]]), 0.036 * h, look.pants_bgr),
            Part("capsule", np.array([j[f"ankle_{s}"], j[f"toe_{s}"]]), 0.028 * h, look.shoes_bgr),
            Part(
                "capsule",
                np.array([j[f"shoulder_{s}"], j[f"elbow_{s}"]]),
                0.034 * h,
                look.shirt_bgr,
            ),
            Part("capsule", np.array([j[f"elbow_{s}"], j[f"wrist_{s}"]]), 0.028 * h, sleeve),
            Part("sphere", j[f"hand_{s}"][None], 0.03 * h, look.skin_bgr),
        ]
    return parts


def _px(p: np.ndarray) -> tuple[int, int]:
    return (round(float(p[0]) * _ONE), round(float(p[1]) * _ONE))


def _shade(color: tuple[int, int, int], factor: float) -> tuple[float, float, float]:
    return tuple(float(min(255.0, c * factor)) for c in color)  # type: ignore[return-value]


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
    parts = body_parts(height_m, phase_rad, gait, look)
    c, s = math.cos(yaw_rad), math.sin(yaw_rad)
    rot = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
    counts = [len(p.points) for p in parts]
    local = np.concatenate([p.points for p in parts])
    world = local @ rot.T + np.asarray(position_enu, dtype=float)
    cam_pts = pose.to_camera(world)
    pixels, depth = project_camera_points(cam_pts, camera)
    f = camera.fx
    drawn = []
    start = 0
    for part, n in zip(parts, counts, strict=True):
        px, d = pixels[start : start + n], depth[start : start + n]
        start += n
        if np.any(d < NEAR_PLANE_M + part.radius_m):
            continue
        drawn.append((float(d.mean()) + part.depth_bias_m, part, px, d))
    drawn.sort(key=lambda item: -item[0])
    for _, part, px, d in drawn:
        if part.kind == "hull":
            _draw_hull(image, px, part.color_bgr)
        else:
            radius = f * part.radius_m / float(d.mean())
            if part.kind == "sphere":
                _draw_ball(image, px[0], radius, part.color_bgr)
            else:
                _draw_capsule(image, px[0], px[1], radius, part.color_bgr)


def _draw_capsule(image, p0, p1, radius_px: float, color) -> None:
    thick = max(1, round(2.0 * radius_px))
    cv2.line(image, _px(p0), _px(p1), _shade(color, _RIM), thick, cv2.LINE_AA, _SHIFT)
    if radius_px >= 1.5:
        off = _LIGHT_2D * radius_px * 0.22
        inner = max(1, round(2.0 * radius_px * 0.55))
        cv2.line(
            image, _px(p0 + off), _px(p1 + off), _shade(color, 1.0), inner, cv2.LINE_AA, _SHIFT
        )


def _draw_ball(image, p, radius_px: float, color) -> None:
    cv2.circle(
        image, _px(p), max(1, round(radius_px * _ONE)), _shade(color, _RIM), -1, cv2.LINE_AA, _SHIFT
    )
    if radius_px >= 1.5:
        q = p + _LIGHT_2D * radius_px * 0.25
        cv2.circle(
            image,
            _px(q),
            round(radius_px * 0.62 * _ONE),
            _shade(color, 1.0),
            -1,
            cv2.LINE_AA,
            _SHIFT,
        )


def _draw_hull(image, pts: np.ndarray, color) -> None:
    hull = cv2.convexHull(np.round(pts * _ONE).astype(np.int32))
    cv2.fillConvexPoly(image, hull, _shade(color, _RIM), cv2.LINE_AA, _SHIFT)
    centre = pts.mean(axis=0)
    size = float(np.ptp(pts[:, 0]) + np.ptp(pts[:, 1])) / 2.0
    inner = (pts - centre) * 0.72 + centre + _LIGHT_2D * size * 0.08
    hull2 = cv2.convexHull(np.round(inner * _ONE).astype(np.int32))
    cv2.fillConvexPoly(image, hull2, _shade(color, 1.0), cv2.LINE_AA, _SHIFT)
