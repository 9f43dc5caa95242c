"""Frame conversions between the simulator's ENU/FLU world and PX4's NED/FRD MAVLink world.

Pure functions on plain floats (fast for one vehicle, no numpy overhead):
- local ENU (x east, y north, z up) <-> local NED (x north, y east, z down);
- Euler angles FLU->ENU (roll, pitch, yaw; yaw counter-clockwise from east) <->
  FRD->NED (roll, pitch, yaw; yaw clockwise from north);
- angle wrapping and quaternions: :mod:`dronewrapper.rotations`;
- local north/east offsets (m) <-> WGS-84 latitude/longitude (degrees) around a home point
  (azimuthal equidistant projection, as PX4's map projection; exact enough for kilometres).
"""

from __future__ import annotations

import math

from dronewrapper.rotations import wrap_pi

EARTH_RADIUS_M = 6_371_000.0


def enu_to_ned(x: float, y: float, z: float) -> tuple[float, float, float]:
    """A local ENU vector as NED (works for positions and velocities)."""
    return y, x, -z


def ned_to_enu(n: float, e: float, d: float) -> tuple[float, float, float]:
    """A local NED vector as ENU (works for positions and velocities)."""
    return e, n, -d


def yaw_enu_to_ned(yaw_enu: float) -> float:
    """Heading: ENU yaw (CCW from east, rad) -> NED yaw (CW from north, rad, wrapped)."""
    return wrap_pi(math.pi / 2.0 - yaw_enu)


def yaw_ned_to_enu(yaw_ned: float) -> float:
    """Heading: NED yaw (CW from north, rad) -> ENU yaw (CCW from east, rad, wrapped)."""
    return wrap_pi(math.pi / 2.0 - yaw_ned)


def euler_flu_enu_to_frd_ned(roll: float, pitch: float, yaw: float) -> tuple[float, float, float]:
    """Attitude FLU->ENU (ROS convention) as FRD->NED (MAVLink convention), radians.

    Roll keeps its sign (right side down is positive in both), pitch flips (FLU pitch is
    positive nose down, FRD positive nose up), yaw is measured from north clockwise.
    """
    return roll, -pitch, yaw_enu_to_ned(yaw)


def rates_flu_to_frd(p: float, q: float, r: float) -> tuple[float, float, float]:
    """Body angular rates FLU (rad/s) -> FRD (rad/s)."""
    return p, -q, -r


def rotate_by_yaw(x: float, y: float, yaw: float) -> tuple[float, float]:
    """A horizontal vector rotated by ``yaw`` (rad, counter-clockwise in its own frame)."""
    c, s = math.cos(yaw), math.sin(yaw)
    return c * x - s * y, s * x + c * y


def body_up_enu(roll: float, pitch: float, yaw: float) -> tuple[float, float, float]:
    """The body's up axis (FLU z) expressed in ENU: the direction of the rotor thrust."""
    cr, sr = math.cos(roll), math.sin(roll)
    cp, sp = math.cos(pitch), math.sin(pitch)
    cy, sy = math.cos(yaw), math.sin(yaw)
    # third column of Rz(yaw) Ry(pitch) Rx(roll)
    return cy * sp * cr + sy * sr, sy * sp * cr - cy * sr, cp * cr


def offset_to_geodetic(
    north_m: float, east_m: float, lat0_deg: float, lon0_deg: float
) -> tuple[float, float]:
    """Latitude/longitude (deg) of a point ``north_m``/``east_m`` from (lat0, lon0)."""
    lat0 = math.radians(lat0_deg)
    lon0 = math.radians(lon0_deg)
    x = north_m / EARTH_RADIUS_M
    y = east_m / EARTH_RADIUS_M
    c = math.hypot(x, y)
    if c < 1e-12:
        return lat0_deg, lon0_deg
    sin_c, cos_c = math.sin(c), math.cos(c)
    lat = math.asin(cos_c * math.sin(lat0) + x * sin_c * math.cos(lat0) / c)
    lon = lon0 + math.atan2(y * sin_c, c * math.cos(lat0) * cos_c - x * math.sin(lat0) * sin_c)
    return math.degrees(lat), math.degrees(lon)


def geodetic_to_offset(
    lat_deg: float, lon_deg: float, lat0_deg: float, lon0_deg: float
) -> tuple[float, float]:
    """North/east offsets (m) of (lat, lon) from (lat0, lon0); inverse of offset_to_geodetic."""
    lat, lon = math.radians(lat_deg), math.radians(lon_deg)
    lat0, lon0 = math.radians(lat0_deg), math.radians(lon0_deg)
    cos_d_lon = math.cos(lon - lon0)
    arg = math.sin(lat0) * math.sin(lat) + math.cos(lat0) * math.cos(lat) * cos_d_lon
    c = math.acos(max(-1.0, min(1.0, arg)))
    k = 1.0 if abs(c) < 1e-12 else c / math.sin(c)
    north = k * (math.cos(lat0) * math.sin(lat) - math.sin(lat0) * math.cos(lat) * cos_d_lon)
    east = k * math.cos(lat) * math.sin(lon - lon0)
    return north * EARTH_RADIUS_M, east * EARTH_RADIUS_M
