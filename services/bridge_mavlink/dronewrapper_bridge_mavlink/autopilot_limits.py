"""The autopilot's own return and fence behaviour, kept consistent with the envelope (pure).

The autopilot flies some things without the bridge: its return (RTL) climbs to its return
altitude first, and its fence fires its own action. Left at their defaults a breach "return"
climbs to PX4's 30 m (``RTL_RETURN_ALT``) above a 15 m ceiling, and a fence breach the
autopilot sees first holds instead of returning. So the bridge writes the autopilot's
parameters whenever the envelope or the autopilot changes (:func:`sync`, an operation):

- the return altitude: ``min(default, max_altitude - RETURN_ALT_BELOW_CEILING_M)`` m above
  home (PX4 ``RTL_RETURN_ALT`` and ``RTL_DESCEND_ALT`` in m; ArduPilot ``RTL_ALT`` in cm), at
  least :data:`MIN_RETURN_ALT_M`. A return then never climbs above the ceiling (it starts at
  the current height when that is higher, and a breach is declared before that is far above).
- the fence action: the envelope's ``breach_action`` (PX4 ``GF_ACTION`` 2 hold, 3 return,
  5 land; ArduPilot ``FENCE_ACTION`` 4 brake, 1 RTL, 2 land), so whichever fence fires first,
  the action taken is the one asked for.

:func:`wanted` is the pure table (tested alone); what was written is remembered per
autopilot and envelope, so :func:`sync` costs nothing when nothing changed. A write the
autopilot refuses is reported as a bridge text and in :attr:`Limits.problem` (a return is
then flown anyway: the message says which altitude the autopilot keeps).
"""

from __future__ import annotations

import logging
from collections.abc import Generator
from dataclasses import dataclass
from typing import TYPE_CHECKING

from dronewrapper.envelope import Envelope
from dronewrapper.msgs.mavros import ParamSet, ParamValue
from dronewrapper_bridge_mavlink import parameters
from dronewrapper_bridge_mavlink.modes import AUTOPILOT_ARDUPILOT, AUTOPILOT_PX4

if TYPE_CHECKING:
    from dronewrapper_bridge_mavlink.core import BridgeCore

log = logging.getLogger("bridge_mavlink")

RETURN_ALT_BELOW_CEILING_M = 1.0
MIN_RETURN_ALT_M = 2.0
PX4_RETURN_ALT_M = 30.0  # PX4's RTL_RETURN_ALT default
PX4_DESCEND_ALT_M = 10.0  # PX4's RTL_DESCEND_ALT default
ARDUPILOT_RETURN_ALT_M = 15.0  # ArduCopter's RTL_ALT default (1500 cm)
PX4_FENCE_ACTION = {"hold": 2, "return": 3, "land": 5}
ARDUPILOT_FENCE_ACTION = {"hold": 4, "return": 1, "land": 2}


@dataclass
class Limits:
    """What the bridge last wrote: for which (autopilot, envelope), and a problem ("" none)."""

    written_for: tuple[str, Envelope] | None = None
    problem: str = ""
    running: bool = False


def return_altitude(envelope: Envelope, default: float) -> float:
    """The return altitude (m above home) under ``envelope``'s ceiling."""
    ceiling = envelope.max_altitude - RETURN_ALT_BELOW_CEILING_M
    return max(MIN_RETURN_ALT_M, min(default, ceiling))


def wanted(autopilot: str, envelope: Envelope) -> list[tuple[str, float, bool]]:
    """The parameters to write: (name, value, integer)."""
    if autopilot == AUTOPILOT_ARDUPILOT:
        alt = return_altitude(envelope, ARDUPILOT_RETURN_ALT_M)
        return [
            ("RTL_ALT", float(round(alt * 100.0)), True),
            ("FENCE_ACTION", float(ARDUPILOT_FENCE_ACTION[envelope.breach_action]), True),
        ]
    alt = return_altitude(envelope, PX4_RETURN_ALT_M)
    return [
        ("RTL_RETURN_ALT", alt, False),
        ("RTL_DESCEND_ALT", min(PX4_DESCEND_ALT_M, alt), False),
        ("GF_ACTION", float(PX4_FENCE_ACTION[envelope.breach_action]), True),
    ]


def sync(core: BridgeCore) -> Generator[float, None, str]:
    """Write :func:`wanted` unless already written for this autopilot and envelope; the
    problem ("" when all were taken)."""
    limits: Limits = core.missions.limits
    while limits.running:  # one writer at a time; the other waits for its result
        yield core.now + 0.05
    autopilot = core.autopilot or AUTOPILOT_PX4
    key = (autopilot, core.missions.envelope)
    if limits.written_for == key or not core.connected:
        return limits.problem
    limits.running = True
    try:
        problems = []
        for name, value, integer in wanted(autopilot, key[1]):
            number = ParamValue(integer=int(value)) if integer else ParamValue(real=value)
            reply = yield from parameters.param_set(core, ParamSet(param_id=name, value=number))
            if not reply.success:
                problems.append(f"{name}={value:g}: {reply.message}")
        limits.problem = "; ".join(problems)
        limits.written_for = key
    finally:
        limits.running = False
    if limits.problem:
        core.bridge_text(
            f"the autopilot's return or fence may leave the envelope: {limits.problem}"
        )
    else:
        log.info("autopilot return and fence set for the envelope: %s", wanted(autopilot, key[1]))
    return limits.problem


def sync_steps(core: BridgeCore) -> Generator[float, None, str]:
    """:func:`sync` as a background operation (the core starts it on connect and on a new
    envelope)."""
    return (yield from sync(core))


__all__ = ["Limits", "return_altitude", "sync", "wanted"]
