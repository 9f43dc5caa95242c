"""The unattended-action rule on bridge_mavlink's core (pure): a go-to, mission or return whose
commander's process disappeared ends as for a lost commander once the action has ended
(:mod:`~dronewrapper_bridge_base.unattended`).

The core (its :class:`~dronewrapper_bridge_base.guided_core.GuidedCore` part) hears the
commanders' beats and each change of mode or arming; it calls :func:`tick` each stream tick,
which says when the aircraft holds on its own (:func:`holding`), over the core as
:class:`WatchPort` shows it.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Protocol

from dronewrapper_bridge_base.unattended import Unattended
from dronewrapper_bridge_mavlink import operations as ops
from dronewrapper_bridge_mavlink.mission_state import MissionState
from dronewrapper_bridge_mavlink.modes import AUTOPILOT_PX4, HOLD_MODE

NAV_FIRST, NAV_LAST = 16, 99  # MAV_CMD_NAV_*: the items that fly somewhere


class WatchPort(ops.Heard, Protocol):
    """What the watch reads and calls of the core besides the autopilot as heard (kind,
    ``""`` before a heartbeat; its mode): the mission flown, the unattended rule and its
    tick."""

    missions: MissionState
    unattended: Unattended

    def unattended_tick(self, holding: Callable[[], bool]) -> None: ...


def holding(core: WatchPort) -> bool:
    """The aircraft holds on its own: the autopilot's hold mode, or a mission flown to its last
    item that flies somewhere (a NAV_* command; the camera or speed items after it are never
    reported reached: a QGroundControl survey ends with its camera trigger off)."""
    autopilot = core.autopilot or AUTOPILOT_PX4
    missions = core.missions
    flown = [i for i, wp in enumerate(missions.waypoints) if NAV_FIRST <= wp.command <= NAV_LAST]
    last = flown[-1] if flown else len(missions.waypoints) - 1
    done = bool(missions.waypoints) and missions.last_reached >= last
    return ops.shown_mode(core) == HOLD_MODE[autopilot] or (
        core.unattended.what == "mission" and done
    )


def tick(core: WatchPort) -> None:
    """Take the unattended action when its time has come (once)."""
    core.unattended_tick(lambda: holding(core))
