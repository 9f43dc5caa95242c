"""Missions from what users have: a QGroundControl ``.plan`` file or a list of waypoints.

:func:`waypoints_of` turns either into mission items
(:class:`~dronewrapper.msgs.mission.Waypoint`):

* a ``.plan`` path (or its parsed JSON document): its ``mission.items`` of type
  ``SimpleItem`` as they are (command, frame, the seven params: lat, lon and alt are params
  5-7; ``null`` is NaN). A ``ComplexItem`` (survey, corridor scan) is refused:
  QGroundControl expands it only when it uploads.
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
from os import PathLike
from pathlib import Path
from typing import Any

from dronewrapper.msgs.mission import FRAME_GLOBAL_REL_ALT, NAV_WAYPOINT, Waypoint

FRAME_LOCAL_ENU = 4
ACCEPTANCE_RADIUS_M = 0.5


class PlanError(ValueError):
    """A plan that cannot be flown; the message says where and why."""


def _number(value: Any, where: str) -> float:
    if value is None:
        return math.nan
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise PlanError(f"{where}: expected a number, got {value!r}")
    return float(value)


def read_plan(path: str | PathLike[str]) -> list[Waypoint]:
    """The mission items of a QGroundControl ``.plan`` file."""
    path = Path(path)
    try:
        document = json.loads(path.read_text())
    except (OSError, json.JSONDecodeError) as exc:
        raise PlanError(f"{path}: not a readable .plan file ({exc})") from None
    return parse_plan(document, path.name)


def parse_plan(document: Any, name: str = "plan") -> list[Waypoint]:
    """The mission items of a parsed ``.plan`` document (``name`` says where in errors)."""
    if not isinstance(document, dict) or document.get("fileType") != "Plan":
        raise PlanError(f"{name}: not a QGroundControl plan (fileType is not 'Plan')")
    mission = document.get("mission")
    items = mission.get("items") if isinstance(mission, dict) else None
    if not isinstance(items, list):
        raise PlanError(f"{name}: no mission.items list")
    waypoints = []
    for number, item in enumerate(items):
        where = f"{name}: mission item {number}"
        if not isinstance(item, dict) or item.get("type") != "SimpleItem":
            kind = item.get("type") if isinstance(item, dict) else type(item).__name__
            raise PlanError(
                f"{where}: a {kind} is not supported (only SimpleItem: QGroundControl expands "
                "surveys and scans into simple items when it uploads them)"
            )
        params = item.get("params", [])
        if not isinstance(params, list) or len(params) != 7:
            raise PlanError(f"{where}: params must be a list of 7 values")
        p = [_number(value, f"{where} param {i + 1}") for i, value in enumerate(params)]
        try:
            waypoints.append(
                Waypoint(
                    frame=int(item.get("frame", FRAME_GLOBAL_REL_ALT)),
                    command=int(item["command"]),
                    autocontinue=bool(item.get("autoContinue", True)),
                    param1=0.0 if math.isnan(p[0]) else p[0],
                    param2=0.0 if math.isnan(p[1]) else p[1],
                    param3=0.0 if math.isnan(p[2]) else p[2],
                    param4=p[3],
                    x_lat=0.0 if math.isnan(p[4]) else p[4],
                    y_long=0.0 if math.isnan(p[5]) else p[5],
                    z_alt=0.0 if math.isnan(p[6]) else p[6],
                )
            )
        except (KeyError, TypeError, ValueError) as exc:
            raise PlanError(f"{where}: {exc}") from None
    if not waypoints:
        raise PlanError(f"{name}: the plan has no mission items")
    return waypoints


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


def waypoints_of(
    plan: str | PathLike[str] | Sequence[Any], *, frame: str = "global"
) -> list[Waypoint]:
    """Mission items of ``plan`` (see module docstring)."""
    if frame not in ("global", "local"):
        raise PlanError(f"frame must be 'global' or 'local', got {frame!r}")
    if isinstance(plan, str | PathLike):
        return read_plan(plan)
    if isinstance(plan, Mapping):
        return parse_plan(dict(plan))
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


__all__ = ["FRAME_LOCAL_ENU", "PlanError", "parse_plan", "read_plan", "waypoints_of"]
