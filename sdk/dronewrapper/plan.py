"""Missions from what users have: a QGroundControl ``.plan`` file or a list of waypoints.

:func:`waypoints_of` turns either into mission items
(:class:`~dronewrapper.msgs.mission.Waypoint`):

* a ``.plan`` path (or its parsed JSON document), as QGroundControl writes it: its
  ``mission.items`` of type ``SimpleItem`` as they are (command, frame, the seven params: lat,
  lon and alt are params 5-7, the altitude in the item's frame: 3 above home, 0 AMSL, 10
  above terrain); a ``ComplexItem`` (survey, corridor scan) as the items QGroundControl
  expanded it into (``TransectStyleComplexItem.Items``), in order; one without them
  (a structure scan) is refused. A ``null`` param is 0 (unused), except a null altitude or
  position of an item that flies to one (:data:`NEEDS_ALTITUDE`, :data:`NEEDS_POSITION`:
  QGroundControl's "calculated" or unset altitude), which is refused, naming the item and its
  command. The plan's ``geoFence`` and ``rallyPoints`` are read too
  (:mod:`dronewrapper.plan_fence`), for the caller to carry or refuse.
* a list of ``(lat, lon, alt)``: NAV_WAYPOINT items, degrees and metres above home, each
  reached within :data:`ACCEPTANCE_RADIUS_M` (the autopilot's default, PX4's NAV_ACC_RAD, is
  2 m).
* with ``frame="local"``, a list of ``(x, y, z)``: ENU metres from home, MAV_FRAME_LOCAL_ENU
  items (what a drone without GPS, the Tello, flies; the bridge uploads them to a GPS
  autopilot as global items), with the same acceptance radius.
"""

from __future__ import annotations

import json
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from os import PathLike
from pathlib import Path
from typing import Any

from dronewrapper.msgs.mission import (
    FRAME_GLOBAL_REL_ALT,
    NAV_WAYPOINT,
    Waypoint,
    command_name,
)
from dronewrapper.plan_fence import PlanFence, parse_fence

FRAME_LOCAL_ENU = 4
ACCEPTANCE_RADIUS_M = 0.5
# MAV_CMDs whose param7 is the altitude flown to (a null one is refused, never 0 m AMSL),
# and those whose params 5-6 are the place flown to (a null one is refused)
NEEDS_ALTITUDE = {16, 17, 18, 19, 22, 31, 82, 84}
NEEDS_POSITION = {16, 17, 18, 19, 31, 82}


class PlanError(ValueError):
    """A plan that cannot be flown; the message says where and why."""


@dataclass(frozen=True)
class Plan:
    """What a ``.plan`` file holds: its mission items, flattened in upload order, and its
    fence and rally points (:class:`~dronewrapper.plan_fence.PlanFence`)."""

    waypoints: list[Waypoint]
    fence: PlanFence = field(default_factory=PlanFence)


def _number(value: Any, where: str) -> float:
    if value is None:
        return math.nan
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise PlanError(f"{where}: expected a number, got {value!r}")
    return float(value)


def read_document(path: str | PathLike[str]) -> dict[str, Any]:
    """The parsed JSON of a ``.plan`` file."""
    path = Path(path)
    try:
        return json.loads(path.read_text())
    except (OSError, json.JSONDecodeError) as exc:
        raise PlanError(f"{path}: not a readable .plan file ({exc})") from None


def read_plan(path: str | PathLike[str]) -> Plan:
    """The mission, fence and rally points of a QGroundControl ``.plan`` file."""
    return parse_plan(read_document(path), Path(path).name)


def _simple_items(items: list[Any], name: str) -> list[tuple[str, dict[str, Any]]]:
    """(where, SimpleItem) in upload order: a complex item contributes its expanded items."""
    flat = []
    for number, item in enumerate(items):
        where = f"mission.items[{number}]"
        kind = item.get("type") if isinstance(item, dict) else type(item).__name__
        if kind == "SimpleItem":
            flat.append((where, item))
            continue
        if kind != "ComplexItem":
            raise PlanError(f"{name}: {where}: a {kind} is not a SimpleItem or ComplexItem")
        complex_type = f"{item.get('complexItemType') or ''} ComplexItem".lstrip()
        transect = item.get("TransectStyleComplexItem")
        expanded = transect.get("Items") if isinstance(transect, dict) else None
        if not isinstance(expanded, list) or not expanded:
            raise PlanError(
                f"{name}: {where}: a {complex_type} without its expanded items "
                "(TransectStyleComplexItem.Items, which QGroundControl writes for surveys and "
                "corridor scans): QGroundControl computes them only when it uploads"
            )
        for inner, sub in enumerate(expanded):
            sub_where = f"{where} ({complex_type.removesuffix(' ComplexItem')}) Items[{inner}]"
            if not isinstance(sub, dict) or sub.get("type", "SimpleItem") != "SimpleItem":
                raise PlanError(f"{name}: {sub_where}: not a SimpleItem")
            flat.append((sub_where, sub))
    return flat


def _waypoint(item: dict[str, Any], where: str) -> Waypoint:
    """One SimpleItem as a Waypoint (``where`` names it in errors)."""
    params = item.get("params", [])
    if not isinstance(params, list) or len(params) != 7:
        raise PlanError(f"{where}: params must be a list of 7 values")
    p = [_number(value, f"{where} param {i + 1}") for i, value in enumerate(params)]
    command = item.get("command")
    if isinstance(command, bool) or not isinstance(command, int):
        raise PlanError(f"{where}: command must be a MAV_CMD number, got {command!r}")
    if command in NEEDS_ALTITUDE and math.isnan(p[6]):
        raise PlanError(
            f"{where}: the altitude is null (QGroundControl's 'calculated' or unset "
            "altitude): set it in QGroundControl, never 0 m AMSL"
        )
    if command in NEEDS_POSITION and (math.isnan(p[4]) or math.isnan(p[5])):
        raise PlanError(f"{where}: the latitude or longitude is null")
    try:
        return Waypoint(
            frame=int(item.get("frame", FRAME_GLOBAL_REL_ALT)),
            command=command,
            autocontinue=bool(item.get("autoContinue", True)),
            param1=0.0 if math.isnan(p[0]) else p[0],
            param2=0.0 if math.isnan(p[1]) else p[1],
            param3=0.0 if math.isnan(p[2]) else p[2],
            param4=p[3],
            x_lat=0.0 if math.isnan(p[4]) else p[4],
            y_long=0.0 if math.isnan(p[5]) else p[5],
            z_alt=0.0 if math.isnan(p[6]) else p[6],
        )
    except (TypeError, ValueError) as exc:
        raise PlanError(f"{where}: {exc}") from None


def parse_plan(document: Any, name: str = "plan") -> Plan:
    """The plan in a parsed ``.plan`` document (``name`` says where in errors)."""
    if not isinstance(document, dict) or document.get("fileType") != "Plan":
        raise PlanError(f"{name}: not a QGroundControl plan (fileType is not 'Plan')")
    mission = document.get("mission")
    items = mission.get("items") if isinstance(mission, dict) else None
    if not isinstance(items, list):
        raise PlanError(f"{name}: no mission.items list")
    waypoints = []
    for seq, (where, item) in enumerate(_simple_items(items, name)):
        label = f"{name}: mission item {seq} ({where}, {command_name(item.get('command', -1))})"
        waypoints.append(_waypoint(item, label))
    if not waypoints:
        raise PlanError(f"{name}: the plan has no mission items")
    try:
        fence = parse_fence(document)
    except ValueError as exc:
        raise PlanError(f"{name}: {exc}") from None
    return Plan(waypoints, fence)


def _triples(points: Sequence[Any], names: str) -> list[tuple[float, float, float]]:
    out = []
    for number, point in enumerate(points):
        try:
            a, b, c = (float(v) for v in point)
        except (TypeError, ValueError):
            raise PlanError(f"waypoint {number} must be ({names}), got {point!r}") from None
        if not all(math.isfinite(v) for v in (a, b, c)):
            raise PlanError(f"waypoint {number} must be finite, got {point!r}")
        out.append((a, b, c))
    if not out:
        raise PlanError("the mission has no waypoints")
    return out


def load_plan(
    plan: str | PathLike[str] | Mapping[str, Any] | Sequence[Any], *, frame: str = "global"
) -> Plan:
    """The :class:`Plan` of a ``.plan`` path or document, or of a list of points (see module
    docstring; a list has no fence)."""
    if isinstance(plan, str | PathLike):
        return read_plan(plan)
    if isinstance(plan, Mapping):
        return parse_plan(dict(plan))
    return Plan(waypoints_of(plan, frame=frame))


def waypoints_of(
    plan: str | PathLike[str] | Mapping[str, Any] | Sequence[Any], *, frame: str = "global"
) -> list[Waypoint]:
    """Mission items of ``plan`` (see module docstring)."""
    if frame not in ("global", "local"):
        raise PlanError(f"frame must be 'global' or 'local', got {frame!r}")
    if isinstance(plan, str | PathLike | Mapping):
        return load_plan(plan).waypoints
    if frame == "local":
        return [
            Waypoint(
                frame=FRAME_LOCAL_ENU,
                command=NAV_WAYPOINT,
                x_lat=x,
                y_long=y,
                z_alt=z,
                param2=ACCEPTANCE_RADIUS_M,
            )
            for x, y, z in _triples(plan, "x, y, z")
        ]
    try:
        return [
            Waypoint(x_lat=lat, y_long=lon, z_alt=alt, param2=ACCEPTANCE_RADIUS_M)
            for lat, lon, alt in _triples(plan, "lat, lon, alt")
        ]
    except ValueError as exc:
        raise PlanError(str(exc)) from None


__all__ = [
    "FRAME_LOCAL_ENU",
    "Plan",
    "PlanError",
    "load_plan",
    "parse_plan",
    "read_plan",
    "waypoints_of",
]
