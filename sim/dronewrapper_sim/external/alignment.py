"""Where the autopilot's vehicle is in the scenario's world.

The scenario wins the local frame: the vehicle's first truth sample is placed at the scenario's
start (x, y on the ground, facing the scenario's yaw), and every later sample is moved with it
(one translation and one rotation about the vertical). The autopilot keeps its own geographic
home (the bridge reports its latitude and longitude): nothing is sent to it. Heights are above
the first sample's altitude (the vehicle starts on the ground). Positions are local ENU (m),
angles roll/pitch/yaw of the body FLU in ENU (rad, yaw CCW from east). Pure.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from dronewrapper.rotations import rpy_from_quat, wrap_pi
from dronewrapper_sim.external.truth import GeoTruth

EARTH_RADIUS_M = 6371000.0  # PX4's map projection radius: the same local metres as the bridge


@dataclass(frozen=True)
class LocalTruth:
    """A truth sample in the scenario's frame: ENU position (m), roll/pitch/yaw (rad, FLU in
    ENU), ENU velocity (m/s) and yaw rate (rad/s, CCW)."""

    position: tuple[float, float, float]
    rpy: tuple[float, float, float]
    velocity: tuple[float, float, float]
    yaw_rate: float


def enu_attitude(truth: GeoTruth) -> tuple[float, float, float]:
    """(roll, pitch, yaw) of the body FLU in ENU from the FRD -> NED quaternion."""
    w, x, y, z = truth.q_wxyz
    roll, pitch, yaw_ned = rpy_from_quat((x, y, z, w))
    return roll, -pitch, wrap_pi(math.pi / 2.0 - yaw_ned)


def enu_yaw_rate(truth: GeoTruth) -> float:
    """The heading's rate of change (rad/s, CCW) from the body rates (FRD)."""
    w, x, y, z = truth.q_wxyz
    roll, pitch, _ = rpy_from_quat((x, y, z, w))
    _, q, r = truth.rates_frd
    cos_pitch = max(math.cos(pitch), 1e-6)
    return -(q * math.sin(roll) + r * math.cos(roll)) / cos_pitch


class Alignment:
    """Maps an autopilot's truth into the scenario's frame (see module doc).

    Args:
        origin: the first truth sample (the vehicle on the ground at its start).
        start_x, start_y: the scenario's vehicle start (ENU m).
        start_yaw: the scenario's vehicle heading at start (rad, CCW from east).
    """

    def __init__(self, origin: GeoTruth, start_x: float, start_y: float, start_yaw: float) -> None:
        self.lat0 = origin.lat_deg
        self.lon0 = origin.lon_deg
        self.alt0 = origin.alt_m
        self.start = (start_x, start_y)
        self.rotation = wrap_pi(start_yaw - enu_attitude(origin)[2])
        self._cos = math.cos(self.rotation)
        self._sin = math.sin(self.rotation)
        self._m_per_deg = math.radians(1.0) * EARTH_RADIUS_M
        self._cos_lat0 = math.cos(math.radians(self.lat0))

    def _turn(self, east: float, north: float) -> tuple[float, float]:
        return (self._cos * east - self._sin * north, self._sin * east + self._cos * north)

    def local(self, truth: GeoTruth) -> LocalTruth:
        """``truth`` in the scenario's frame."""
        north = (truth.lat_deg - self.lat0) * self._m_per_deg
        east = (truth.lon_deg - self.lon0) * self._m_per_deg * self._cos_lat0
        x, y = self._turn(east, north)
        vn, ve, vd = truth.vel_ned
        vx, vy = self._turn(ve, vn)
        roll, pitch, yaw = enu_attitude(truth)
        return LocalTruth(
            position=(self.start[0] + x, self.start[1] + y, truth.alt_m - self.alt0),
            rpy=(roll, pitch, wrap_pi(yaw + self.rotation)),
            velocity=(vx, vy, -vd),
            yaw_rate=enu_yaw_rate(truth),
        )
