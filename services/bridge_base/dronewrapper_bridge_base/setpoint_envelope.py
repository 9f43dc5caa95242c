"""A valid setpoint checked against the safety envelope (pure), as both PX4-capable bridges
(MAVLink, PX4 over Zenoh) apply it before it may fly.

A position setpoint's point is checked as ENU m from home; a velocity setpoint's velocity
against the envelope's speed limits, and a mixed one's altitude (its z from home, m) against
its ceiling. A refusal is also said to the ground as a bridge warning, at most every
:data:`REFUSAL_TEXT_PERIOD_S` s.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Protocol

from dronewrapper import envelope as env
from dronewrapper.envelope import Envelope, EnvelopeError
from dronewrapper.msgs.mavros import PositionTarget
from dronewrapper_bridge_base.setpoint_limits import Kind

REFUSAL_TEXT_PERIOD_S = 2.0  # at most one "setpoint refused" text this often


class EnvelopeAndHome(Protocol):
    """What a bridge's envelope state holds for the check."""

    envelope: Envelope
    home_local: tuple[float, float, float]  # home in the autopilot's local frame (ENU m)
    last_refusal_text: float  # when a refusal was last said (monotonic s)


def refuse_setpoint(
    state: EnvelopeAndHome,
    target: PositionTarget,
    kind: Kind,
    now: float,
    say: Callable[[str], object],
) -> EnvelopeError | None:
    """Why the envelope refuses ``target`` (valid, of control ``kind``; the limit named), or
    None; ``say`` is given the refusal at most every :data:`REFUSAL_TEXT_PERIOD_S` s."""
    try:
        if kind is Kind.POSITION:
            p = target.required_position()
            hx, hy, hz = state.home_local
            env.check_position(state.envelope, p.x - hx, p.y - hy, p.z - hz)
        else:
            v = target.velocity
            env.check_velocity(state.envelope, v.x, v.y, v.z)
            if kind is Kind.MIXED:
                z = target.required_position().z - state.home_local[2]
                if z > state.envelope.max_altitude:
                    raise EnvelopeError(
                        f"altitude {z:g} m above the envelope's {state.envelope.max_altitude:g} m",
                        "max_altitude",
                    )
    except EnvelopeError as exc:
        if now - state.last_refusal_text >= REFUSAL_TEXT_PERIOD_S:
            state.last_refusal_text = now
            say(f"setpoint refused: {exc}")
        return exc
    return None
