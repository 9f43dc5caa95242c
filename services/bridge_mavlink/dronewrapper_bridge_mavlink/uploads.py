"""The lists the bridge uploads besides the mission: the autopilot's fence (from the envelope)
and its rally points (pure, over two parts the core owns: its
:class:`~dronewrapper_bridge_mavlink.transfers.Transfers` and its
:class:`~dronewrapper_bridge_mavlink.mission_state.MissionState`).

:func:`item_of` and :func:`waypoint_of` convert between the bus's Waypoint and
MISSION_ITEM_INT content. :func:`push_fence` uploads the envelope as MAV_MISSION_TYPE_FENCE
(:func:`fence_items`); :func:`push_rally` uploads rally points as MAV_MISSION_TYPE_RALLY
(NAV_RALLY_POINT items, global frames, numbered from 0 on every autopilot: no home item).
Frames: WGS-84, home's geodetic position plus a flat-earth offset.
"""

from __future__ import annotations

import logging
from collections.abc import Generator
from typing import Protocol

from pymavlink.dialects.v20 import common as mavlink

from dronewrapper.envelope import Envelope
from dronewrapper.geodesy import to_geodetic
from dronewrapper.msgs.mission import MissionResult, Waypoint, WaypointClear
from dronewrapper.runtime import ServiceError
from dronewrapper_bridge_base.operation import Steps
from dronewrapper_bridge_mavlink import mission_transfer as mt
from dronewrapper_bridge_mavlink.mission_state import MissionState
from dronewrapper_bridge_mavlink.transfers import Transfers

log = logging.getLogger("bridge_mavlink")

FENCE_BACKUP_M = 5.0  # m the autopilot's fence circle lies beyond the bridge's breach
FENCE_INCLUSION = mavlink.MAV_CMD_NAV_FENCE_POLYGON_VERTEX_INCLUSION
FENCE_EXCLUSION = mavlink.MAV_CMD_NAV_FENCE_POLYGON_VERTEX_EXCLUSION
FENCE_CIRCLE = mavlink.MAV_CMD_NAV_FENCE_CIRCLE_INCLUSION


class UploadPort(Protocol):
    """What an upload uses of the core: whether the autopilot is heard, its mission state
    (envelope, home, rally points) and its transfers."""

    missions: MissionState
    transfers: Transfers

    def require_connected(self) -> str: ...


ALIKE = ("frame", "command", "param1", "param2", "param3", "param4")
"""What a Waypoint and a MISSION_ITEM_INT carry alike; the flags are bools on the bus, the
position degrees there and degrees * 1e7 in the item."""


def item_of(waypoint: Waypoint) -> mt.Item:
    """A Waypoint as MISSION_ITEM_INT content (degrees * 1e7)."""
    return mt.Item(
        **{name: getattr(waypoint, name) for name in ALIKE},
        current=int(waypoint.is_current),
        autocontinue=int(waypoint.autocontinue),
        x=round(waypoint.x_lat * 1e7),
        y=round(waypoint.y_long * 1e7),
        z=waypoint.z_alt,
    )


def waypoint_of(item: mt.Item) -> Waypoint:
    """MISSION_ITEM_INT content as a Waypoint (degrees)."""
    return Waypoint(
        **{name: getattr(item, name) for name in ALIKE},
        is_current=bool(item.current),
        autocontinue=bool(item.autocontinue),
        x_lat=item.x / 1e7,
        y_long=item.y / 1e7,
        z_alt=item.z,
    )


def fence_items(envelope: Envelope, home: tuple[float, float, float]) -> list[mt.Item]:
    """``envelope`` as MAV_MISSION_TYPE_FENCE items around ``home`` (deg, deg, m AMSL): a
    circle of max_distance plus the margin and :data:`FENCE_BACKUP_M` (the autopilot's fence
    is the backstop: the bridge acts first), the inclusion polygon, the exclusion zones."""
    frame = mavlink.MAV_FRAME_GLOBAL
    items = [
        mt.Item(
            frame=frame,
            command=FENCE_CIRCLE,
            param1=envelope.max_distance + envelope.margin + FENCE_BACKUP_M,
            x=round(home[0] * 1e7),
            y=round(home[1] * 1e7),
        )
    ]
    polygons = [(FENCE_INCLUSION, envelope.fence)] if envelope.fence else []
    polygons += [(FENCE_EXCLUSION, zone) for zone in envelope.exclusions]
    for command, polygon in polygons:
        for east, north in polygon:
            lat, lon = to_geodetic(home, east, north)
            items.append(
                mt.Item(
                    frame=frame,
                    command=command,
                    param1=float(len(polygon)),
                    x=round(lat * 1e7),
                    y=round(lon * 1e7),
                )
            )
    return items


def push_fence(core: UploadPort, _request: WaypointClear) -> Steps:
    """geofence/push: upload the envelope's fence to the autopilot (MAV_MISSION_TYPE_FENCE),
    so it holds even if this bridge stops."""
    core.require_connected()
    state = core.missions
    if state.home_geo is None:
        raise ServiceError("home is not known yet: the fence cannot be placed", "refused")
    items = fence_items(state.envelope, state.home_geo)
    upload = yield from core.transfers.upload(items, mission_type=mt.FENCE)
    if upload.error:
        log.warning("fence upload: %s", upload.error)
    message = upload.error or f"fence of {len(items)} item(s) uploaded"
    return MissionResult(success=not upload.error, message=message)


def push_rally(
    transfers: Transfers, state: MissionState, rally: list[Waypoint]
) -> Generator[float, None, str]:
    """Upload ``rally`` (checked, in a global frame) by ``transfers`` as the autopilot's rally
    points (MAV_MISSION_TYPE_RALLY, no home item on any autopilot; ``[]`` clears them); on
    success they are ``state.rally``. Returns the error, "" on success."""
    items = [item_of(wp) for wp in rally]
    upload = yield from transfers.upload(items, mission_type=mt.RALLY)
    if upload.error:
        log.warning("rally upload: %s", upload.error)
        return f"the mission was uploaded, its rally points were not: {upload.error}"
    state.rally = rally
    return ""


__all__ = [
    "FENCE_BACKUP_M",
    "UploadPort",
    "fence_items",
    "item_of",
    "push_fence",
    "push_rally",
    "waypoint_of",
]
