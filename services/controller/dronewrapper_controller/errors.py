"""The paper's error terms (sections 4.1.2 and 4.2.2), made safe.

Image pixels: origin top-left, x right, y down. To make one set of gains work at any camera
resolution, pixel quantities are expressed in pixels of a *reference image* ``ref_width`` px
wide (320 px: the paper's simulated camera), i.e. multiplied by ``ref_width / image_width``.
Sign convention (our PIDs compute ``u = K * e``, no hidden ``0 - input``):

- ``e_z   = c_y - obj_y``  (ref px): positive when the object is above the image centre -> climb.
- ``e_yaw = c_x - obj_x``  (ref px): positive when the object is left of centre -> turn left
  (yaw counter-clockwise positive, ENU/FLU).
- follow-colour ``e_x = (radius - target_radius) / target_radius`` (dimensionless, float; the
  original used integer division): positive when the blob looks too big (too close), so the
  forward gain is negative.
- follow-person ``e_x = total_area / det_area - total_area / target_area`` with
  ``total_area / target_area = 20``: positive when the person looks too small (too far), so the
  forward gain is positive. The original was unbounded (a 20x20 px person gave e_x = 172 and
  8.6 m/s); here it is clamped to ``[-max_forward_error, +max_forward_error]``.
"""

from __future__ import annotations

import math

import msgspec

from dronewrapper.msgs.vision import Detection2D


class ServoErrors(msgspec.Struct, kw_only=True, frozen=True):
    """The three error terms of one frame (see the module doc for units and signs)."""

    x: float
    z: float
    yaw: float


def _check_image(width: float, height: float) -> None:
    if not (width > 0 and height > 0):
        raise ValueError(f"image size must be positive, got {width}x{height}")


def centre_errors(
    obj_x: float, obj_y: float, width: float, height: float, ref_width: float
) -> tuple[float, float]:
    """``(e_z, e_yaw)`` in reference pixels for an object centred at ``(obj_x, obj_y)`` px."""
    _check_image(width, height)
    scale = ref_width / width
    return (height / 2.0 - obj_y) * scale, (width / 2.0 - obj_x) * scale


def colour_forward_error(radius: float, width: float, target_radius: float, ref_width: float):
    """Paper eq. (1): ``(radius - target_radius) / target_radius``, radius scaled to ref px.

    Args:
        radius: radius of the blob's minimum enclosing circle (px of the source image).
        width: source image width (px).
        target_radius: wanted radius in reference px (10 px at 320 px wide: about 5 m).
        ref_width: reference image width (px).
    """
    if not target_radius > 0:
        raise ValueError(f"target_radius must be > 0, got {target_radius}")
    _check_image(width, 1)
    return (radius * ref_width / width - target_radius) / target_radius


def person_forward_error(
    det_area: float, total_area: float, area_ratio: float, max_error: float
) -> float:
    """Paper eq. (4): ``total_area/det_area - area_ratio``, clamped to ``+-max_error``.

    Args:
        det_area: area of the person's bounding box (px^2); <= 0 gives ``+max_error``.
        total_area: image area (px^2).
        area_ratio: ``total_area / target_area`` (the paper's 20: the person fills 1/20).
        max_error: bound of the result (dimensionless).
    """
    if not (total_area > 0 and area_ratio > 0 and max_error > 0):
        raise ValueError("total_area, area_ratio and max_error must be > 0")
    if not det_area > 0:
        return max_error
    return max(-max_error, min(max_error, total_area / det_area - area_ratio))


def blob_radius(det: Detection2D) -> float:
    """The blob's enclosing-circle radius (px), or half the larger box side when not given."""
    if det.circle_radius > 0:
        return det.circle_radius
    return max(det.bbox.size_x, det.bbox.size_y) / 2.0


def follow_color_errors(
    det: Detection2D, width: float, height: float, target_radius: float, ref_width: float
) -> ServoErrors:
    """All three follow-colour errors for one detection."""
    c = det.bbox.center.position
    e_z, e_yaw = centre_errors(c.x, c.y, width, height, ref_width)
    e_x = colour_forward_error(blob_radius(det), width, target_radius, ref_width)
    return ServoErrors(x=e_x, z=e_z, yaw=e_yaw)


def follow_person_errors(
    det: Detection2D,
    width: float,
    height: float,
    area_ratio: float,
    max_forward_error: float,
    ref_width: float,
) -> ServoErrors:
    """All three follow-person errors for one detection (box centre and box area)."""
    c = det.bbox.center.position
    e_z, e_yaw = centre_errors(c.x, c.y, width, height, ref_width)
    area = det.bbox.size_x * det.bbox.size_y
    e_x = person_forward_error(area, width * height, area_ratio, max_forward_error)
    return ServoErrors(x=e_x, z=e_z, yaw=e_yaw)


def finite(errors: ServoErrors) -> bool:
    """True when every term is a finite number."""
    return all(math.isfinite(v) for v in (errors.x, errors.z, errors.yaw))
