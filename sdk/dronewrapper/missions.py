"""A DroneWrapper's missions: upload a plan, follow its progress.

* ``upload_mission(plan)`` (a QGroundControl ``.plan`` path, or a list of ``(lat, lon,
  alt)``; ``frame="local"``: ``(x, y, z)`` ENU m from home): one request
  (``{ns}/mavros/mission/push``); a plan's fence is folded into the bridge's envelope first.
* ``mission_progress()``: the item being flown and those reached, as the bridge publishes them
  (``{ns}/mavros/mission/waypoints``, ``.../reached``).

Flying it (``start_mission``, ``pause_mission``, ``resume_mission``) is a bridge operation
answered at its end, as take-off is: :mod:`dronewrapper.flights`.
"""

from __future__ import annotations

import logging
import math
import threading
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from os import PathLike
from typing import Any

from dronewrapper import plan_fence
from dronewrapper.client import DroneClient
from dronewrapper.commands import Commands
from dronewrapper.envelope import Envelope
from dronewrapper.envelope_guard import EnvelopeGuard
from dronewrapper.errors import DroneError, InvalidArgument, NoData
from dronewrapper.msgs import registry
from dronewrapper.msgs.mission import WaypointList, WaypointPush, WaypointReached
from dronewrapper.plan import PlanError, load_plan
from dronewrapper.plan_fence import PlanFence
from dronewrapper.runtime.latest import Latest

log = logging.getLogger("dronewrapper")
NAV_COMMANDS_START = 16  # MAV_CMD_NAV_WAYPOINT: the NAV_* commands are 16-99


@dataclass(frozen=True)
class MissionProgress:
    """Where the mission stands: ``current`` (the item being flown, 0-based), ``total``
    items, ``reached`` (the last item reached, 0-based; None until one is heard reached) and
    ``reached_items`` (every item reported reached since the upload, in order, each once:
    PX4 and our simulator report the items that fly somewhere, not speed or camera items).
    ``last_flown`` is the last item that flies somewhere (a ``NAV_*`` command); None: the last
    item."""

    current: int
    total: int
    reached: int | None = None
    reached_items: tuple[int, ...] = ()
    last_flown: int | None = None

    @property
    def reached_count(self) -> int:
        """How many distinct items have been reached."""
        return len(self.reached_items)

    @property
    def finished(self) -> bool:
        """The last item that flies somewhere was reached. The speed, camera and payload items
        after it (a QGroundControl survey ends with its camera trigger off) are never reported
        reached, so they are not waited for; a mission with no such item never reads
        finished."""
        end = self.total - 1 if self.last_flown is None else self.last_flown
        return self.total > 0 and self.reached is not None and self.reached >= end


class Missions:
    """Upload and progress of one drone's mission (see the module doc); a part a DroneWrapper
    owns.

    Args:
        client: the drone client (its holders of the mission list and of the items reached).
        commands: the drone's service calls; ``guard``: its envelope (a plan's fence).
    """

    def __init__(self, client: DroneClient, commands: Commands, guard: EnvelopeGuard) -> None:
        self.ns = client.ns
        self.commands = commands
        self.guard = guard
        self._waypoints: Latest[WaypointList] = client.inputs.latest(registry.MISSION_WAYPOINTS)
        self._reached: Latest[WaypointReached] = client.inputs.latest(registry.MISSION_REACHED)
        self._lock = threading.Lock()
        self._reached_items: list[int] = []  # every item reached since the last upload
        self._last_reached: int | None = None  # the item last reached since the last upload
        self._reached.listen(self._on_reached)

    def _on_reached(self) -> None:
        reached = self._reached.value
        if reached is None:
            return
        with self._lock:
            self._last_reached = reached.wp_seq
            if reached.wp_seq not in self._reached_items:
                self._reached_items.append(reached.wp_seq)

    def upload_mission(
        self,
        plan: str | PathLike[str] | Mapping[str, Any] | Sequence[Any],
        *,
        frame: str = "global",
        returns_home: bool = False,
        timeout: float = 30.0,
    ) -> int:
        """Upload a mission: a QGroundControl ``.plan`` path (or its parsed JSON), or a list
        of ``(lat, lon, alt)`` (degrees, m above home); ``frame="local"``: ``(x, y, z)`` ENU
        m from home (the Tello's only kind). Returns the number of items.

        A plan's ``geoFence`` is folded into the envelope first (:mod:`dronewrapper.plan_fence`;
        it stays after the mission, put back if the upload fails); a breach-return point is
        refused unless ``returns_home`` accepts returns to home. A plan's rally points are
        uploaded with it as the autopilot's (checked against the envelope; a plan without
        them clears the autopilot's; a list of points leaves them as they are); a backend
        without rally points (the Tello) refuses a plan that has some.

        Raises:
            InvalidArgument: the plan cannot be read or flown, or its fence cannot be held.
            NoData: the plan has a fence and home's position is not known yet.
            CommandRefused: an item or rally point is outside the envelope, or the autopilot
                refused the upload (naming the item it refused and its command).
        """
        try:
            loaded = load_plan(plan, frame=frame)
        except PlanError as exc:
            raise InvalidArgument(f"upload_mission: {exc}") from None
        before = self._fold(loaded.fence, returns_home, timeout) if loaded.fence.folds else None
        document = isinstance(plan, str | PathLike | Mapping)
        rally = plan_fence.rally_waypoints(loaded.fence) if document else None
        push = WaypointPush(waypoints=loaded.waypoints, rally=rally)
        try:
            reply = self.commands.command(registry.MISSION_PUSH, push, "upload_mission", timeout)
        except DroneError:
            if before is not None:
                self.guard.put(before, "upload_mission", timeout)
            raise
        with self._lock:
            self._reached_items.clear()  # the last mission's items are not this one's
            self._last_reached = None
        return reply.wp_transfered

    def _fold(self, fence: PlanFence, returns_home: bool, timeout: float) -> Envelope:
        """Carry a plan's fence into the bridge's envelope; returns the envelope before."""
        home = self.guard.home_holder.value
        if home is None or math.isnan(home.latitude):
            raise NoData("upload_mission: the plan has a fence, and home is not known yet")
        current = self.guard.envelope(timeout=timeout)
        try:
            wanted = plan_fence.fold(
                fence, current, (home.latitude, home.longitude), returns_home=returns_home
            )
        except ValueError as exc:
            raise InvalidArgument(f"upload_mission: {exc}") from None
        if wanted != current:
            self.guard.put(wanted, "upload_mission", timeout)
        return current

    def mission_progress(self) -> MissionProgress:
        """The mission's progress as the bridge last published it."""
        listing = self._waypoints.value
        if listing is None:
            raise NoData(f"no mission list yet on {registry.MISSION_WAYPOINTS.key(self.ns)}")
        with self._lock:
            reached, items = self._last_reached, tuple(self._reached_items)
        return MissionProgress(
            current=listing.current_seq,
            total=len(listing.waypoints),
            reached=reached,
            reached_items=items,
            last_flown=_last_flown(listing),
        )


def _last_flown(listing: WaypointList) -> int | None:
    """The index of the last item that flies somewhere (MAV_CMD_NAV_*: 16-99), or None."""
    flown = [i for i, wp in enumerate(listing.waypoints) if NAV_COMMANDS_START <= wp.command < 100]
    return flown[-1] if flown else None


__all__ = ["MissionProgress", "Missions"]
