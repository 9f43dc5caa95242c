"""Geodetic points <-> ENU metres around home (flat earth: within the envelope's kilometre the
error is millimetres). Degrees WGS-84; metres east and north of ``home`` = (lat, lon, ...)."""

from __future__ import annotations

import math
from collections.abc import Sequence

EARTH_RADIUS_M = 6_378_137.0  # WGS-84 equatorial radius


def to_geodetic(home: Sequence[float], east: float, north: float) -> tuple[float, float]:
    """(lat, lon) degrees of the point ``east``, ``north`` m from ``home``."""
    lat0, lon0 = home[0], home[1]
    lat = lat0 + math.degrees(north / EARTH_RADIUS_M)
    lon = lon0 + math.degrees(east / (EARTH_RADIUS_M * math.cos(math.radians(lat0))))
    return lat, lon


def to_enu(home: Sequence[float], lat: float, lon: float) -> tuple[float, float]:
    """(east, north) m of (lat, lon) degrees from ``home``."""
    lat0, lon0 = home[0], home[1]
    north = math.radians(lat - lat0) * EARTH_RADIUS_M
    east = math.radians(lon - lon0) * EARTH_RADIUS_M * math.cos(math.radians(lat0))
    return east, north
