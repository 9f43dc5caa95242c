"""Mission items in the frames people write them, placed and checked against the envelope (pure).

The envelope is ENU m in the home frame. A mission item is placed there by its frame:

- global frames (MAV_FRAME_GLOBAL 0 / GLOBAL_INT 5: altitude AMSL; GLOBAL_RELATIVE_ALT 3 / 6:
  m above home; GLOBAL_TERRAIN_ALT 10 / 11: m above the ground, taken as above home, the
  terrain being unknown to the bridge): latitude and longitude from home's geodetic position;
  an AMSL altitude minus home's AMSL altitude.
- local frames (MAV_FRAME_LOCAL_ENU 4, the SDK's ``frame="local"``; LOCAL_NED 1): x, y, z m
  from home. An autopilot flies global items (PX4 takes no local mission items), so a local
  item is uploaded as GLOBAL_RELATIVE_ALT at home plus its offset; that needs home's
  latitude and longitude (GPS).
- MAV_FRAME_MISSION (2) and an item at (0, 0): no position (a speed change, a return).

:func:`placed` gives an item's ENU position from home (None: no position); :func:`prepare`
checks every item against the envelope (the first one outside named with the limit) and
returns the items to upload. Rally points (NAV_RALLY_POINT) are placed and checked the same
way: a return must not fly outside the envelope either (and how high a return to one climbs:
:mod:`~dronewrapper_bridge_mavlink.rally_returns`).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import msgspec

from dronewrapper import envelope as env
from dronewrapper.envelope import Envelope, EnvelopeError
from dronewrapper.geodesy import to_enu, to_geodetic
from dronewrapper.msgs.mission import FRAME_GLOBAL_REL_ALT, Waypoint

GLOBAL_AMSL = (0, 5)
GLOBAL_RELATIVE = (3, 6)
GLOBAL_TERRAIN = (10, 11)
LOCAL_ENU = 4
LOCAL_NED = 1
NO_POSITION = (2,)


class MissionFrameError(ValueError):
    """An item that cannot be placed or is outside the envelope; the message names it."""


def placed(wp: Waypoint, home_geo: Sequence[float] | None) -> tuple[float, float, float] | None:
    """(east, north, up) m from home of ``wp``, None when it carries no position.

    Raises:
        MissionFrameError: a global item before home's geodetic position is known, or an
            unknown frame.
    """
    frame = wp.frame
    if frame == LOCAL_ENU:
        return (wp.x_lat, wp.y_long, wp.z_alt)
    if frame == LOCAL_NED:
        return (wp.y_long, wp.x_lat, -wp.z_alt)
    if frame in NO_POSITION:
        return None
    if frame not in GLOBAL_AMSL + GLOBAL_RELATIVE + GLOBAL_TERRAIN:
        raise MissionFrameError(f"frame {frame} is not a mission frame the bridge can place")
    horizontal = wp.x_lat != 0.0 or wp.y_long != 0.0
    if home_geo is None or (frame in GLOBAL_AMSL and math.isnan(home_geo[2])):
        if not horizontal and frame not in GLOBAL_AMSL:
            return (0.0, 0.0, wp.z_alt)
        raise MissionFrameError(
            "home is not known yet: the mission cannot be checked against the envelope"
        )
    east, north = to_enu(home_geo, wp.x_lat, wp.y_long) if horizontal else (0.0, 0.0)
    up = wp.z_alt - home_geo[2] if frame in GLOBAL_AMSL else wp.z_alt
    return (east, north, up)


def uploadable(wp: Waypoint, home_geo: Sequence[float] | None) -> Waypoint:
    """``wp`` as the autopilot takes it: a local item becomes GLOBAL_RELATIVE_ALT."""
    if wp.frame not in (LOCAL_ENU, LOCAL_NED):
        return wp
    if home_geo is None or math.isnan(home_geo[0]):
        raise MissionFrameError(
            "a local-frame item needs home's latitude and longitude (GPS) to be uploaded"
        )
    east, north, up = placed(wp, home_geo) or (0.0, 0.0, 0.0)
    lat, lon = to_geodetic(home_geo, east, north)
    return msgspec.structs.replace(wp, frame=FRAME_GLOBAL_REL_ALT, x_lat=lat, y_long=lon, z_alt=up)


def prepare(
    waypoints: Sequence[Waypoint],
    envelope: Envelope,
    home_geo: Sequence[float] | None,
    *,
    what: str = "mission item",
) -> list[Waypoint]:
    """The items to upload, every positioned one checked against ``envelope``.

    Raises:
        MissionFrameError: naming the first item that cannot be placed or is outside
            (``what`` and its number: ``mission item 2``, ``rally point 0``).
    """
    out = []
    for seq, wp in enumerate(waypoints):
        try:
            position = placed(wp, home_geo)
            if position is not None:
                env.check_position(envelope, *position)
            out.append(uploadable(wp, home_geo))
        except (EnvelopeError, MissionFrameError) as exc:
            raise MissionFrameError(f"{what} {seq}: {exc}") from None
    return out


__all__ = ["MissionFrameError", "placed", "prepare", "uploadable"]
