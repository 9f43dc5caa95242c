"""The safety envelope a PX4-capable bridge holds and the home it is measured from, as a part of
the core with its own state (:class:`EnvelopeState`; bridge_mavlink's ``MissionState`` adds
the mission to it).

Its rules: a take-off above the ceiling is refused (:meth:`~EnvelopeState.refuse_takeoff`),
and the guided mode while the aircraft is outside (:meth:`~EnvelopeState.refuse_mode`: a
breach action must not be undone by a commander); :meth:`~EnvelopeState.watch` declares a
breach of the armed, airborne aircraft once per excursion (the core reports it and runs
``breach_action``). A setpoint's check is
:func:`~dronewrapper_bridge_base.setpoint_envelope.refuse_setpoint`, on this state; a
replacement's is :mod:`~dronewrapper_bridge_base.envelope_set`.

Frames: the envelope is ENU m in the home frame; ``home_local`` is home in the autopilot's
local frame (ENU m; the local origin until home is known), ``home_geo`` its geodetic position
(deg, deg, m AMSL; None until known).
"""

from __future__ import annotations

import math
from typing import Protocol

from dronewrapper import envelope as env
from dronewrapper.envelope import Envelope, EnvelopeError
from dronewrapper.msgs.mission import HomePosition
from dronewrapper.msgs.std import Header
from dronewrapper.runtime import ServiceError
from dronewrapper_bridge_base.breach import BreachMonitor


class Flying(Protocol):
    """Whether the aircraft is armed and airborne (the core's failsafe knows)."""

    @property
    def armed(self) -> bool: ...
    @property
    def airborne(self) -> bool: ...


class BreachReporter(Protocol):
    """What :func:`watch_breach` uses of a core: the pose, the failsafe's view of the aircraft,
    and where a breach is said (a bridge warning) and reported (to whoever commands)."""

    @property
    def failsafe(self) -> Flying: ...

    def pose(self) -> tuple[tuple[float, float, float], float] | None: ...
    def bridge_text(self, text: str) -> None: ...
    def report_breach(self, limit: str, reason: str, action: str) -> None: ...


PUBLISH_PERIOD_S = 2.0
"""The envelope and home (and a bridge's mission) are published this often besides on change
(s)."""


class Republished:
    """When a part's state is published again besides on change: every
    :data:`PUBLISH_PERIOD_S`, from its first tick on (``now`` monotonic s)."""

    next_publish = -math.inf

    def publish_due(self, now: float) -> bool:
        """Whether to publish again at ``now``; if so, the next time is set."""
        if now < self.next_publish:
            return False
        self.next_publish = now + PUBLISH_PERIOD_S
        return True


class EnvelopeState(Republished):
    """The envelope in force (``set_by``: who set it, "" the configured one), its breach
    monitor and home (see module docstring)."""

    def __init__(self, envelope: Envelope) -> None:
        self.envelope = envelope
        self.set_by = ""
        self.monitor = BreachMonitor()
        self.home_local: tuple[float, float, float] = (0.0, 0.0, 0.0)
        self.home_geo: tuple[float, float, float] | None = None
        self.last_refusal_text = -math.inf  # when a setpoint's refusal was last said (s)

    def relative(self, x: float, y: float, z: float) -> tuple[float, float, float]:
        """Local ENU (m) -> ENU m from home."""
        hx, hy, hz = self.home_local
        return (x - hx, y - hy, z - hz)

    def refuse_takeoff(self, height: float) -> None:
        """ServiceError (refused) when a take-off to ``height`` m climbs above the envelope."""
        try:
            env.check_takeoff(self.envelope, height)
        except EnvelopeError as exc:
            raise ServiceError(str(exc), "refused") from None

    def refuse_mode(self, mode: str, *, guided: bool) -> None:
        """ServiceError (refused) for ``mode``, the ``guided`` one, while the aircraft is
        outside the envelope (once back inside, the guided mode may be entered again)."""
        if guided and self.monitor.outside:
            raise ServiceError(
                f"{mode} refused: the aircraft is outside the envelope (breach action "
                f"{self.envelope.breach_action} in progress)",
                "refused",
            )

    def breach_state(self) -> str:
        """``breach:<action>`` while the aircraft is outside the envelope, else ""."""
        return f"breach:{self.envelope.breach_action}" if self.monitor.outside else ""

    def watch(self, position: tuple[float, float, float], *, flying: bool) -> str:
        """The aircraft at local ENU ``position`` (m), ``flying`` (armed and airborne): the
        breach's reason when it has just left the envelope (``monitor.limit`` names the
        limit), else ""."""
        if not flying:
            return ""
        return self.monitor.update(self.envelope, self.relative(*position))

    def home_message(self, stamp: float) -> HomePosition:
        """Home as published (``stamp`` Unix s; NaN latitude, longitude and altitude while
        its geodetic position is unknown)."""
        lat, lon, alt = self.home_geo or (math.nan, math.nan, math.nan)
        x, y, z = self.home_local
        return HomePosition(
            header=Header(stamp=stamp), latitude=lat, longitude=lon, altitude=alt, x=x, y=y, z=z
        )


def watch_breach(core: BreachReporter, state: EnvelopeState) -> str:
    """Each stream tick: the envelope's ``breach_action`` when the aircraft has just left
    ``state``'s envelope (said and reported; the core runs it), else ""."""
    pose = core.pose()
    flying = core.failsafe.airborne and core.failsafe.armed
    reason = "" if pose is None else state.watch(pose[0], flying=flying)
    if not reason:
        return ""
    action = state.envelope.breach_action
    core.bridge_text(f"envelope breach: {reason}; {action}")
    core.report_breach(state.monitor.limit, reason, action)
    return action
