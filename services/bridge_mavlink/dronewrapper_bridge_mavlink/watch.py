"""The unattended-action rule on bridge_mavlink's core (pure): a go-to, mission or return whose
commander's process disappeared ends as for a lost commander once the action has ended
(:mod:`~dronewrapper_bridge_base.unattended`).

The core calls :func:`on_alive` with the key of each commander's beat its node receives,
:func:`tick` each stream tick and :func:`on_vehicle` after each change of mode or arming.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from dronewrapper_bridge_mavlink import operations as ops
from dronewrapper_bridge_mavlink.modes import AUTOPILOT_PX4, HOLD_MODE

NAV_FIRST, NAV_LAST = 16, 99  # MAV_CMD_NAV_*: the items that fly somewhere

if TYPE_CHECKING:
    from dronewrapper_bridge_mavlink.core_view import BridgeCore


def on_alive(core: BridgeCore, keys: set[str]) -> None:
    core.unattended.on_alive(keys, core.now)


def on_vehicle(core: BridgeCore) -> None:
    """A disarm ends the watch (the aircraft is down)."""
    hb = core.heartbeat_state
    if hb is not None and not hb.armed and not core.failsafe.airborne:
        core.unattended.clear()


def holding(core: BridgeCore) -> bool:
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


def tick(core: BridgeCore) -> None:
    """Take the unattended action when its time has come (once)."""
    unattended = core.unattended
    if not unattended.what or not core.failsafe.airborne:
        return
    action = unattended.tick(core.now, holding=holding(core))
    if action:
        core.bridge_text(unattended.reason(core.now))
        core.failsafe.release_hold()
        core.start(ops.failsafe_action(core, action), core.now, core.stamp, background=True)
