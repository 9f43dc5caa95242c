"""ArduPilot's mission item 0 is home (pure: the autopilot's kind is all it reads).

ArduPilot keeps home in mission item 0 and flies items 1 on; its MISSION_CURRENT and
MISSION_ITEM_REACHED count from that item 0. PX4 (and our simulator) fly from item 0. The
bridge's mission (``core.missions.waypoints``, the published list, the SDK's items, the item
numbers of ``mission/reached`` and ``mission/set_current``) is the items that fly, numbered
from 0 on every autopilot: on ArduPilot an upload puts a home item before them, a download
drops it, and the autopilot's item numbers are shifted by :func:`offset`.

An upload marks its first item current (MAVLink's ``current``): PX4 keeps its last mission's
current item through an upload that marks none (a new mission flown from item 2 on PX4 SITL,
2026-11-28), ArduPilot reads only ``current`` 2 and 3. After an upload PX4 reports its last
mission's last item reached again (its MAVLink side's reached is reset by the upload, its
navigator's is not): :func:`reached` drops a PX4 item beyond the one being flown, as PX4
sends the new current item (MISSION_CURRENT, 0 after an upload) before the item reached.
"""

from __future__ import annotations

import dataclasses

from pymavlink.dialects.v20 import common as mavlink

from dronewrapper_bridge_mavlink import mission_transfer as mt
from dronewrapper_bridge_mavlink.modes import AUTOPILOT_ARDUPILOT


def offset(autopilot: str) -> int:
    """How many items ``autopilot`` holds before the bridge's first: 1 on ArduPilot, else 0."""
    return 1 if autopilot == AUTOPILOT_ARDUPILOT else 0


def uploaded(
    items: list[mt.Item], autopilot: str, home_geo: tuple[float, float, float] | None
) -> list[mt.Item]:
    """``items`` as ``autopilot`` takes them: the first marked current and, on ArduPilot, a
    home item before them (at ``home_geo``: deg, deg, m AMSL; ArduPilot keeps its own home
    there, never flown)."""
    if items and not any(item.current for item in items):
        items = [dataclasses.replace(items[0], current=1), *items[1:]]
    if not offset(autopilot):
        return items
    lat, lon, alt = home_geo or (0.0, 0.0, 0.0)
    home = mt.Item(
        frame=mavlink.MAV_FRAME_GLOBAL,
        command=mavlink.MAV_CMD_NAV_WAYPOINT,
        x=round(lat * 1e7),
        y=round(lon * 1e7),
        z=alt,
    )
    return [home, *items]


def downloaded(items: list[mt.Item], autopilot: str) -> list[mt.Item]:
    """``autopilot``'s items without its home item."""
    return items[offset(autopilot) :]


def ours(seq: int, autopilot: str) -> int | None:
    """The bridge's number of ``autopilot``'s item ``seq`` (None: ArduPilot's home item)."""
    number = seq - offset(autopilot)
    return number if number >= 0 else None


def theirs(number: int, autopilot: str) -> int:
    """``autopilot``'s number of the bridge's item ``number``."""
    return number + offset(autopilot)


def reached(seq: int, autopilot: str, current: int) -> int | None:
    """The bridge's number of the item ``autopilot`` reports reached, ``current`` the bridge's
    number of the item being flown; None: not this mission's (ArduPilot's home item, or PX4's
    stale report of an item beyond the one flown)."""
    number = ours(seq, autopilot)
    if number is None or (not offset(autopilot) and number > current):
        return None
    return number
