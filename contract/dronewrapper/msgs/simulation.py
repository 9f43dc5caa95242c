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


class PoseSourceStatus(msgspec.Struct, kw_only=True, frozen=True):
    """Where a simulated world takes its vehicle pose from, and how fresh it was in the frames.

    Attributes:
        source: ``builtin`` (the simulator's own physics) or the external autopilot
            (``px4-sih``, ``ardupilot``).
        link: the link the truth arrives on (``udp:127.0.0.1:19410`` ...).
        truth_rate_hz: truth samples received over the last second.
        truth_age_s: how old the newest truth is now (s; NaN before the first).
        frames: camera frames rendered since the last status.
        age_mean_s, age_p95_s, age_max_s: age of the truth each of those frames was rendered
            from, at its capture time (s).
        extrapolated_share: share of those frames whose pose was extrapolated past the newest
            truth (the rest were interpolated between two).
        aligned: the autopilot's start was placed at the scenario's vehicle start.
        rotation_rad: the turn (about the vertical, CCW) from the autopilot's local ENU to the
            scenario's frame.
    """

    source: str
    link: str = ""
    truth_rate_hz: float = 0.0
    truth_age_s: float = float("nan")
    frames: int = 0
    age_mean_s: float = float("nan")
    age_p95_s: float = float("nan")
    age_max_s: float = float("nan")
    extrapolated_share: float = float("nan")
    aligned: bool = False
    rotation_rad: float = 0.0
