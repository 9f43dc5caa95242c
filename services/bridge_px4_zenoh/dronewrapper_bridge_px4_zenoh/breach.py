"""The safety envelope's breach rule on the PX4 Zenoh core (pure): while armed and airborne
outside the envelope, the breach is reported to whoever commands and the envelope's action
runs (``land``, ``return``: PX4's own; ``hold``: AUTO.LOITER). The envelope, home and the
(empty) mission list are published every :data:`PUBLISH_PERIOD_S`. The envelope's checks and
its monitor are bridge_mavlink's (:mod:`dronewrapper_bridge_mavlink.missions`)."""

from __future__ import annotations

from typing import TYPE_CHECKING

from dronewrapper.msgs.mavros import SetMode
from dronewrapper_bridge_base.operation import Steps
from dronewrapper_bridge_mavlink import missions

if TYPE_CHECKING:
    from dronewrapper_bridge_px4_zenoh.core import Px4ZenohCore

PUBLISH_PERIOD_S = 2.0


def tick(core: Px4ZenohCore) -> None:
    """Each stream tick: act on a breach, publish envelope, home and missions periodically."""
    state = core.missions
    pose = core.pose()
    if pose is not None and core.failsafe.airborne and core.failsafe.armed:
        reason = state.monitor.update(state.envelope, missions.relative(core, *pose[0]))
        if reason:
            action = state.envelope.breach_action
            core.bridge_text(f"envelope breach: {reason}; {action}")
            core.report_breach(state.monitor.limit, reason, action)
            core.start(breach_action(core, action), core.now, core.stamp, background=True)
    if core.now >= state._next_publish:
        state._next_publish = core.now + PUBLISH_PERIOD_S
        missions.publish_all(core)


def breach_action(core: Px4ZenohCore, action: str) -> Steps:
    """``land`` or ``return`` (the failsafe's own requests), or ``hold`` (AUTO.LOITER)."""
    from dronewrapper_bridge_px4_zenoh import operations as ops

    if action in ("land", "return"):
        return (yield from ops.failsafe_action(core, action))
    reply = yield from ops.set_mode(core, SetMode(custom_mode=ops.HOLD_MODE))
    return reply.result
