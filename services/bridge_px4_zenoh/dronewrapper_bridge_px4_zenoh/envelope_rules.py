"""Home and the safety envelope on the PX4 Zenoh core (pure), the rules of the SDK's
:mod:`dronewrapper.envelope` as every bridge keeps them:

* a setpoint outside the envelope is refused, the limit named (bridge_base's
  :func:`~dronewrapper_bridge_base.setpoint_envelope.refuse_setpoint`, on this state);
  a take-off above its ceiling too (:func:`refuse_takeoff`), and OFFBOARD while outside it
  (:func:`refuse_mode`: a breach action must not be undone by a commander);
* while armed and airborne outside it, the breach is reported to whoever commands and the
  envelope's action runs (``land``, ``return``: PX4's own; ``hold``: AUTO.LOITER);
* the envelope and home are published every :data:`PUBLISH_PERIOD_S` s; ``envelope/set``
  replaces or resets the envelope (:func:`set_envelope`, the lease holder's only).

Home is PX4's local origin (the estimator's reference, from ``vehicle_local_position``'s
``ref_lat``/``ref_lon``/``ref_alt``): the envelope is ENU m from it. PX4's ``home_position``
is not among its zenoh module's default topics.
"""

from __future__ import annotations

import math
from typing import Any

from dronewrapper import envelope as env
from dronewrapper.envelope import Envelope, EnvelopeError
from dronewrapper.msgs import registry
from dronewrapper.msgs.mission import EnvelopeSet, HomePosition
from dronewrapper.msgs.std import Header
from dronewrapper.runtime import ServiceError
from dronewrapper_bridge_base import envelope_set
from dronewrapper_bridge_base.breach import BreachMonitor
from dronewrapper_bridge_base.operation import Steps

Px4ZenohCore = Any
"""The core (core.py imports this module, so the type is not imported here)."""

PUBLISH_PERIOD_S = 2.0


class EnvelopeState:
    """The envelope in force, its breach monitor and home (local ENU m and geodetic)."""

    def __init__(self, envelope: Envelope) -> None:
        self.envelope = envelope
        self.set_by = ""  # who set the envelope in force ("": the configured one)
        self.monitor = BreachMonitor()
        self.home_local: tuple[float, float, float] = (0.0, 0.0, 0.0)
        self.home_geo: tuple[float, float, float] | None = None  # deg, deg, m AMSL
        self.next_publish = -math.inf
        self.last_refusal_text = -math.inf

    def relative(self, x: float, y: float, z: float) -> tuple[float, float, float]:
        """Local ENU (m) -> ENU m from home."""
        hx, hy, hz = self.home_local
        return (x - hx, y - hy, z - hz)


def refuse_takeoff(core: Px4ZenohCore, height: float) -> None:
    """ServiceError (refused) when a take-off to ``height`` m climbs above the envelope."""
    try:
        env.check_takeoff(core.envelope.envelope, height)
    except EnvelopeError as exc:
        raise ServiceError(str(exc), "refused") from None


def refuse_mode(core: Px4ZenohCore, mode: str) -> None:
    """ServiceError (refused) for OFFBOARD while the aircraft is outside the envelope."""
    state = core.envelope
    if mode == "OFFBOARD" and state.monitor.outside:
        raise ServiceError(
            f"{mode} refused: the aircraft is outside the envelope (breach action "
            f"{state.envelope.breach_action} in progress)",
            "refused",
        )


def breach_state(core: Px4ZenohCore) -> str:
    """``breach:<action>`` while the aircraft is outside the envelope, else ""."""
    state = core.envelope
    return f"breach:{state.envelope.breach_action}" if state.monitor.outside else ""


def tick(core: Px4ZenohCore) -> str:
    """Each stream tick: on a breach, report it and return the envelope's action (the core
    starts it: ``land``, ``return`` or ``hold``), else ""; publish the envelope and home
    periodically."""
    state = core.envelope
    pose = core.pose()
    breach = ""
    if pose is not None and core.failsafe.airborne and core.failsafe.armed:
        reason = state.monitor.update(state.envelope, state.relative(*pose[0]))
        if reason:
            action = state.envelope.breach_action
            core.bridge_text(f"envelope breach: {reason}; {action}")
            core.report_breach(state.monitor.limit, reason, action)
            breach = action
    if core.now >= state.next_publish:
        state.next_publish = core.now + PUBLISH_PERIOD_S
        core.publish(registry.ENVELOPE, state.envelope)
        publish_home(core)
    return breach


def publish_home(core: Px4ZenohCore) -> None:
    state = core.envelope
    lat, lon, alt = state.home_geo or (math.nan, math.nan, math.nan)
    x, y, z = state.home_local
    home = HomePosition(
        header=Header(stamp=core.stamp), latitude=lat, longitude=lon, altitude=alt, x=x, y=y, z=z
    )
    core.publish(registry.HOME_POSITION, home)


def set_envelope(core: Px4ZenohCore, request: EnvelopeSet) -> Steps:
    """envelope/set: replace or reset the envelope (neither: read it; see
    :mod:`dronewrapper_bridge_base.envelope_set`). PX4 gets no fence: the bridge's envelope
    is the only one."""
    state = core.envelope
    pose = core.pose()
    aircraft = None if pose is None else state.relative(*pose[0])[:2]
    changed = envelope_set.apply(
        state, request, configured=core.config.envelope, caller=core.caller, aircraft=aircraft
    )
    if changed:
        core.publish(registry.ENVELOPE, state.envelope)
    yield from ()
    return envelope_set.result(state)
