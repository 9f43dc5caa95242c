"""Follow quality from ground truth (pure): bearing and distance to the target, and a summary.

Used by ``make demo`` and the scenario tests. Frames: local ENU metres, yaw counter-clockwise
from east (radians). The camera looks along the vehicle's heading (frontal camera, no tilt).

- bearing error: horizontal angle between the vehicle's heading and the direction to the
  target (rad, wrapped to [-pi, pi]; positive = target to the left);
- elevation error: vertical angle from the camera's height to the aim point (rad; positive =
  above); the vehicle's own pitch is ignored (it tilts only while accelerating);
- distance: horizontal distance from the vehicle to the target (m).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import msgspec
import numpy as np

from dronewrapper.rotations import wrap_pi

TRACKING_STATES = ("tracking", "hover", "search")  # the controller is servoing (after take-off)


def bearing_error(vehicle_xy: Sequence[float], yaw: float, target_xy: Sequence[float]) -> float:
    """Angle from the heading ``yaw`` to the target, horizontal (rad, + = target on the left)."""
    dx, dy = target_xy[0] - vehicle_xy[0], target_xy[1] - vehicle_xy[1]
    return wrap_pi(math.atan2(dy, dx) - yaw)


def elevation_error(vehicle: Sequence[float], aim: Sequence[float]) -> float:
    """Vertical angle from the vehicle to the aim point (rad, + = above)."""
    horizontal = math.hypot(aim[0] - vehicle[0], aim[1] - vehicle[1])
    return math.atan2(aim[2] - vehicle[2], max(horizontal, 1e-6))


def horizontal_distance(a: Sequence[float], b: Sequence[float]) -> float:
    """Horizontal distance between two ENU points (m)."""
    return math.hypot(b[0] - a[0], b[1] - a[1])


class FollowSample(msgspec.Struct, kw_only=True):
    """One instant of a follow flight.

    Attributes:
        t: seconds since the start of the record.
        vehicle: vehicle position (ENU m) from ground truth; yaw its heading (rad).
        target: the target's aim point (ENU m): beacon centre, a person's chest.
        others: the other objects' aim points by name (ENU m).
        state: the controller's state; target_visible: its view of the target.
    """

    t: float
    vehicle: tuple[float, float, float]
    yaw: float
    target: tuple[float, float, float]
    others: dict[str, tuple[float, float, float]] = msgspec.field(default_factory=dict)
    state: str = ""
    target_visible: bool = False

    @property
    def bearing(self) -> float:
        return bearing_error(self.vehicle, self.yaw, self.target)

    @property
    def elevation(self) -> float:
        return elevation_error(self.vehicle, self.target)

    @property
    def distance(self) -> float:
        return horizontal_distance(self.vehicle, self.target)

    def centred(self, tolerance: float) -> bool:
        """Target within ``tolerance`` rad of the optical axis, horizontally and vertically."""
        return abs(self.bearing) <= tolerance and abs(self.elevation) <= tolerance

    def closest_to_axis(self) -> str:
        """Name of the object nearest the optical axis (bearing): ``target`` or another."""
        best, best_err = "target", abs(self.bearing)
        for name, pos in self.others.items():
            err = abs(bearing_error(self.vehicle, self.yaw, pos))
            if err < best_err:
                best, best_err = name, err
        return best


class FollowSummary(msgspec.Struct, kw_only=True):
    """How well a flight followed its target (after take-off).

    Attributes:
        duration: seconds of servoing recorded (s).
        time_to_acquire: seconds from the start of servoing until the controller saw the target
            and it was centred (s; inf when never).
        centred_share: share of the time after acquisition with the target centred (0..1).
        distance_mean, distance_p95: absolute distance error |d - intended| after acquisition (m).
        distance_share: share of the time after acquisition with |d - intended| <= tolerance.
        bearing_p95: 95th percentile of |bearing error| after acquisition (rad).
        visible_share: share of the time after acquisition the controller saw the target.
    """

    duration: float
    time_to_acquire: float
    centred_share: float
    distance_mean: float
    distance_p95: float
    distance_share: float
    bearing_p95: float
    visible_share: float
    intended_distance: float
    samples: int


def summarize(
    samples: Sequence[FollowSample],
    *,
    intended_distance: float,
    centred_tolerance: float = math.radians(10.0),
    distance_tolerance: float = 1.5,
) -> FollowSummary:
    """Summarize a flight (see :class:`FollowSummary`); samples before servoing are ignored."""
    flying = [s for s in samples if s.state in TRACKING_STATES]
    if not flying:
        nan = math.nan
        return FollowSummary(
            duration=0.0,
            time_to_acquire=math.inf,
            centred_share=0.0,
            distance_mean=nan,
            distance_p95=nan,
            distance_share=0.0,
            bearing_p95=nan,
            visible_share=0.0,
            intended_distance=intended_distance,
            samples=0,
        )
    t0 = flying[0].t
    acquired_at = next(
        (s.t for s in flying if s.target_visible and s.centred(centred_tolerance)), None
    )
    after = [s for s in flying if acquired_at is not None and s.t >= acquired_at]
    if not after:
        after = flying
    dist_err = np.array([abs(s.distance - intended_distance) for s in after])
    bearing = np.array([abs(s.bearing) for s in after])
    return FollowSummary(
        duration=flying[-1].t - t0,
        time_to_acquire=math.inf if acquired_at is None else acquired_at - t0,
        centred_share=float(np.mean([s.centred(centred_tolerance) for s in after])),
        distance_mean=float(dist_err.mean()),
        distance_p95=float(np.percentile(dist_err, 95)),
        distance_share=float(np.mean(dist_err <= distance_tolerance)),
        bearing_p95=float(np.percentile(bearing, 95)),
        visible_share=float(np.mean([s.target_visible for s in after])),
        intended_distance=intended_distance,
        samples=len(after),
    )


def focal_px(width: float, hfov_rad: float) -> float:
    """Pinhole focal length in px of a camera ``width`` px wide with horizontal FOV ``hfov_rad``."""
    return width / 2.0 / math.tan(hfov_rad / 2.0)


def colour_intended_distance(
    target_radius: float, ref_width: float, width: float, hfov_rad: float, radius_m: float
) -> float:
    """The distance (m) at which a sphere of ``radius_m`` shows ``target_radius`` reference px.

    ``target_radius`` is in px of a ``ref_width`` image (see dronewrapper_controller.errors).
    """
    radius_px = target_radius * width / ref_width
    return focal_px(width, hfov_rad) * radius_m / radius_px


def person_intended_distance(
    area_ratio: float,
    width: float,
    height: float,
    hfov_rad: float,
    person_h: float,
    person_w: float,
) -> float:
    """The distance (m) at which a person's box fills ``1 / area_ratio`` of the image."""
    f = focal_px(width, hfov_rad)
    return math.sqrt(area_ratio * f * f * person_h * person_w / (width * height))
