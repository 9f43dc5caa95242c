"""PX4's geofence in the simulator: the fence uploaded as a mission list (circle and polygon
inclusion, polygon exclusion) checked against the vehicle's position; a breach in the air
starts GF_ACTION (2 hold, 3 return, 5 land) once per excursion, as PX4's geofence does.

Pure: time is the caller's (s), positions local ENU m; ``to_local(lat, lon)`` gives the local
(east, north) of a geodetic point.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

from pymavlink.dialects.v20 import common as mavlink

from dronewrapper.envelope import inside
from dronewrapper_sim.px4.mission import FENCE, MissionStore
from dronewrapper_sim.px4.modes import Mode

GF_ACTIONS = {2: Mode.LOITER, 3: Mode.RTL, 5: Mode.LAND}  # PX4's GF_ACTION values flown here
BREACH_TEXT = "Geofence exceeded"


@dataclass(frozen=True)
class Breach:
    """An excursion out of the fence began: the mode GF_ACTION flies (None: warn only)."""

    mode: Mode | None


class Geofence:
    """The uploaded fence as local shapes, and its breach check (see module docstring)."""

    def __init__(self, store: MissionStore, to_local: Callable[[float, float], tuple]) -> None:
        self.store = store
        self.to_local = to_local
        self._version = -1
        self.circles: list[tuple[bool, float, float, float]] = []  # inclusion, x, y, r
        self.polygons: list[tuple[bool, list[tuple[float, float]]]] = []
        self.outside = False

    def _load(self) -> None:
        self._version = self.store.fence_version
        self.circles, self.polygons = [], []
        items = self.store.lists[FENCE]
        i = 0
        while i < len(items):
            item = items[i]
            x, y = self.to_local(item.x / 1e7, item.y / 1e7)
            if item.command in (
                mavlink.MAV_CMD_NAV_FENCE_CIRCLE_INCLUSION,
                mavlink.MAV_CMD_NAV_FENCE_CIRCLE_EXCLUSION,
            ):
                inclusion = item.command == mavlink.MAV_CMD_NAV_FENCE_CIRCLE_INCLUSION
                self.circles.append((inclusion, x, y, item.param1))
                i += 1
            elif item.command in (
                mavlink.MAV_CMD_NAV_FENCE_POLYGON_VERTEX_INCLUSION,
                mavlink.MAV_CMD_NAV_FENCE_POLYGON_VERTEX_EXCLUSION,
            ):
                count = max(1, int(item.param1))
                vertices = [self.to_local(v.x / 1e7, v.y / 1e7) for v in items[i : i + count]]
                inclusion = item.command == mavlink.MAV_CMD_NAV_FENCE_POLYGON_VERTEX_INCLUSION
                self.polygons.append((inclusion, vertices))
                i += count
            else:
                i += 1

    def violated(self, x: float, y: float) -> bool:
        """True when (x, y) (local ENU m) is outside an inclusion or inside an exclusion."""
        if self._version != self.store.fence_version:
            self._load()
        for inclusion, cx, cy, radius in self.circles:
            if (math.hypot(x - cx, y - cy) <= radius) != inclusion:
                return True
        return any(inside(vertices, x, y) != inclusion for inclusion, vertices in self.polygons)

    def breach(self, x: float, y: float) -> bool:
        """True once per excursion: the first check outside after being inside."""
        violated = self.violated(x, y)
        first = violated and not self.outside
        self.outside = violated
        return first

    def check(self, gf_action: float, x: float, y: float) -> Breach | None:
        """The breach (x, y) starts (once per excursion; call it only in the air) with the
        mode parameter GF_ACTION asks for, or None."""
        if not self.breach(x, y):
            return None
        return Breach(GF_ACTIONS.get(int(gf_action)))
