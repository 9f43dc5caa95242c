"""Home and the safety envelope on the PX4 Zenoh core (pure, over the core as
:class:`EnvelopePort` shows it; the part holding them: bridge_base's
:class:`~dronewrapper_bridge_base.envelope_state.EnvelopeState`), the rules of
the SDK's :mod:`dronewrapper.envelope` as every bridge keeps them:

* a setpoint outside the envelope is refused, the limit named (bridge_base's
  :func:`~dronewrapper_bridge_base.setpoint_envelope.refuse_setpoint`, on this state);
  a take-off above its ceiling too (:func:`refuse_takeoff`), and OFFBOARD while outside it
  (:func:`refuse_mode`: a breach action must not be undone by a commander);
* while armed and airborne outside it, the breach is reported to whoever commands and the
  envelope's action runs (``land``, ``return``: PX4's own; ``hold``: AUTO.LOITER);
* the envelope and home are published every
  :data:`~dronewrapper_bridge_base.envelope_state.PUBLISH_PERIOD_S` s; ``envelope/set``
  replaces or resets the envelope (:func:`set_envelope`, the lease holder's only).

Home is PX4's local origin (the estimator's reference, from ``vehicle_local_position``'s
``ref_lat``/``ref_lon``/``ref_alt``): the envelope is ENU m from it. PX4's ``home_position``
is not among its zenoh module's default topics.
"""

from __future__ import annotations

from typing import Protocol

from dronewrapper.msgs import registry
from dronewrapper.msgs.mission import EnvelopeSet
from dronewrapper_bridge_base import envelope_set
from dronewrapper_bridge_base.core_view import Serving
from dronewrapper_bridge_base.envelope_state import BreachReporter, EnvelopeState, watch_breach
from dronewrapper_bridge_base.operation import Steps
from dronewrapper_bridge_px4_zenoh.config import Config


class Enveloped(Protocol):
    """The envelope and home the core holds (its part :class:`EnvelopeState`)."""

    envelope: EnvelopeState


class EnvelopePort(Enveloped, Serving, BreachReporter, Protocol):
    """What the envelope's watch, publication and ``envelope/set`` use of the core besides
    its envelope part, a service operation's (time, samples, the caller) and a breach's
    report: the configured envelope."""

    config: Config


def refuse_takeoff(core: Enveloped, height: float) -> None:
    """ServiceError (refused) when a take-off to ``height`` m climbs above the envelope."""
    core.envelope.refuse_takeoff(height)


def refuse_mode(core: Enveloped, mode: str) -> None:
    """ServiceError (refused) for OFFBOARD while the aircraft is outside the envelope."""
    core.envelope.refuse_mode(mode, guided=mode == "OFFBOARD")


def tick(core: EnvelopePort) -> str:
    """Each stream tick: on a breach, report it and return the envelope's action (the core
    starts it: ``land``, ``return`` or ``hold``), else ""; publish the envelope and home
    periodically."""
    state = core.envelope
    breach = watch_breach(core, state)
    if state.publish_due(core.now):
        core.publish(registry.ENVELOPE, state.envelope)
        publish_home(core)
    return breach


def publish_home(core: EnvelopePort) -> None:
    core.publish(registry.HOME_POSITION, core.envelope.home_message(core.stamp))


def set_envelope(core: EnvelopePort, request: EnvelopeSet) -> Steps:
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
