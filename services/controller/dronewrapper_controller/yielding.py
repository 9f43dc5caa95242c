"""When the controller must stop commanding: a landing it did not order (pure).

Another commander (the ground station, an SDK app, a pilot's switch) or the bridge's failsafe
may land the aircraft while the controller servos. From then on the controller's commands are
not wanted: a search turn at up to its yaw rate, or a forward speed, would fight the landing or
lift the aircraft again. :class:`ForeignLanding` names such a landing from the autopilot's
State mode and landed state; the controller then stops commanding and does not command again
until it is started again (a new take-off is a new run).
"""

from __future__ import annotations

from dronewrapper.msgs.mavros import (
    LANDED_STATE_IN_AIR,
    LANDED_STATE_LANDING,
    LANDED_STATE_ON_GROUND,
)

LANDING_MODES = ("AUTO.LAND", "LAND", "AUTO.RTL", "RTL", "AUTO.PRECLAND")
"""Autopilot modes (MAVROS names, PX4 and ArduPilot) that bring the aircraft down."""


class ForeignLanding:
    """Watches the aircraft while the controller servos; :meth:`reason` says why to yield."""

    def __init__(self) -> None:
        self.airborne = False
        """The aircraft was seen in the air while servoing (so on the ground means landed)."""

    def reason(self, mode: str | None, landed_state: int | None) -> str | None:
        """Why the controller must stop commanding now, or None to go on.

        Args:
            mode: the newest State's mode (None before one arrived).
            landed_state: the newest ExtendedState's ``landed_state`` (None before one).
        """
        if landed_state == LANDED_STATE_IN_AIR:
            self.airborne = True
        if not self.airborne:  # servoing on the ground (no take-off asked): nothing to yield to
            return None
        if mode in LANDING_MODES:
            return f"the autopilot is in {mode}, a landing the controller did not order"
        if landed_state == LANDED_STATE_LANDING:
            return "the aircraft is landing, ordered by another commander"
        if landed_state == LANDED_STATE_ON_GROUND:
            return "the aircraft landed, ordered by another commander"
        return None
