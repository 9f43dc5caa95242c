"""What changed while the autopilot link was down (pure), so it is reported when it returns.

A failsafe that happens while the link is down (the autopilot's own RTL or land on data-link
loss, a disarm, an emergency) would otherwise look like an ordinary new state. On reconnection
the state the autopilot reports is compared with the last one heard before the gap, and every
difference is named.
"""

from __future__ import annotations

from pymavlink.dialects.v20 import common as mavlink

from dronewrapper.msgs.mavros import State


def _status(value: int) -> str:
    entry = mavlink.enums["MAV_STATE"].get(value)
    return entry.name.removeprefix("MAV_STATE_") if entry is not None else str(value)


def gap_changes(before: State, after: State) -> list[str]:
    """The differences between the last state before a link gap and the first one after."""
    changes = []
    if before.mode != after.mode:
        changes.append(f"mode {before.mode or '?'} -> {after.mode or '?'}")
    if before.armed != after.armed:
        changes.append("disarmed" if before.armed else "armed")
    if before.system_status != after.system_status:
        changes.append(
            f"system status {_status(before.system_status)} -> {_status(after.system_status)}"
        )
    if before.autopilot != after.autopilot:
        changes.append(f"autopilot {before.autopilot} -> {after.autopilot}")
    return changes


def gap_report(before: State | None, after: State, gap_s: float) -> str | None:
    """A sentence for the log and STATUSTEXT, or None when nothing changed (or no history)."""
    if before is None:
        return None
    changes = gap_changes(before, after)
    if not changes:
        return None
    return f"while the autopilot link was down ({gap_s:.1f} s): " + ", ".join(changes)
