"""Messages of the simulator's world control (not part of any real aircraft)."""

from __future__ import annotations

import msgspec


class WorldLoad(msgspec.Struct, kw_only=True, forbid_unknown_fields=True, frozen=True):
    """Load a scenario's world into a running simulator: its objects (beacon, people) start
    again from their scripted beginnings; the aircraft stays where it is.

    Attributes:
        scenario: a scenario name the simulator knows (see :class:`WorldState.available`);
            the same name as the running one resets the world.
    """

    scenario: str


class WorldQuery(msgspec.Struct, kw_only=True, forbid_unknown_fields=True, frozen=True):
    """Ask a simulator which world it runs (no fields)."""


class VehicleReset(msgspec.Struct, kw_only=True, forbid_unknown_fields=True, frozen=True):
    """Put one simulated vehicle back at its start pose, on the ground, motors off (no
    fields): "reset the drone" between two tries. Its world and battery stay as they are."""


class VehicleResetResult(msgspec.Struct, kw_only=True, frozen=True):
    """What a reset did.

    Attributes:
        success: the vehicle is at its start pose, on the ground, disarmed.
        message: what was done, or why not.
    """

    success: bool
    message: str = ""


class WorldState(msgspec.Struct, kw_only=True, frozen=True):
    """The world a simulator runs.

    Attributes:
        scenario: the running scenario's name.
        objects: the names of its world objects (``target``, ``person1`` ...).
        available: the scenario names it can load.
        loads: how many times a world was loaded since start (0: the one it started with).
    """

    scenario: str
    objects: list[str] = msgspec.field(default_factory=list)
    available: list[str] = msgspec.field(default_factory=list)
    loads: int = 0
