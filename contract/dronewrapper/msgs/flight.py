"""The bridge's long actions: one request each, answered when the manoeuvre has ended.

Take-off, landing, go-to, return and a mission's start, pause and resume. Each bridge flies
them its own way (PX4: a primed setpoint stream, OFFBOARD, arm, climb; ArduPilot: GUIDED, arm,
NAV_TAKEOFF; Tello: ``takeoff``, then a move to the height), so a client sends the same
request to any aircraft and never names an autopilot's modes. Heights in metres above the
take-off point, go-to positions ENU metres from home (home: where the bridge's
``home_position/home`` says), times in seconds.
"""

from __future__ import annotations

import math

import msgspec

REFUSED = "refused"
"""A step was refused (``step`` names it, ``result`` is its MAV_RESULT, -1: unanswered), or
the aircraft gave the manoeuvre up (disarmed, left the mode it was put in)."""
TOO_LATE = "too_late"
"""The manoeuvre's ``timeout`` passed first; the message names the altitude, mode and arming."""
NOT_READY = "not_ready"
"""Nothing to start from: the aircraft is not connected."""
NO_POSITION = "no_position"
"""No local position has arrived, so there is no point to take off from."""
CANCELLED = "cancelled"
"""A cancel request ended it (``{ns}/dronewrapper/cancel``): the aircraft holds where it is."""

NO_HOME = "no_home"
"""Home is not known (within the bridge's bounded wait), or has no latitude and longitude for a
geodetic go-to: the point cannot be placed."""

FAILURES = (REFUSED, TOO_LATE, NOT_READY, NO_POSITION, CANCELLED, NO_HOME)

MISSION_ACTIONS = ("start", "pause", "resume")


class TakeoffRequest(msgspec.Struct, kw_only=True, forbid_unknown_fields=True, frozen=True):
    """Take off and climb to ``height`` m above the take-off point within ``timeout`` s;
    done within ``tolerance`` m of it. Already flying: nothing is done."""

    height: float
    timeout: float = 30.0
    tolerance: float = 0.1


class LandRequest(msgspec.Struct, kw_only=True, forbid_unknown_fields=True, frozen=True):
    """Land where the aircraft is; done once on the ground and disarmed, within ``timeout`` s."""

    timeout: float = 60.0


def _finite(name: str, value: float) -> None:
    if not (isinstance(value, int | float) and math.isfinite(value)):
        raise ValueError(f"{name} must be a finite number, got {value!r}")


class GotoRequest(msgspec.Struct, kw_only=True, forbid_unknown_fields=True, frozen=True):
    """Fly to a point and hold there; done within ``tolerance`` m of it, within ``timeout``
    s. The point: ``x``, ``y`` (ENU m from home), or ``latitude``, ``longitude`` (degrees;
    then ``x``/``y`` stay NaN); ``z`` is m above home either way. ``watch``: the name of the
    commander's process (``{ns}/alive/{name}``, "" none), whose :class:`CommanderBeat` the
    bridge then expects: if the beats stop, the bridge ends the action as for a lost
    commander (docs/design.md)."""

    z: float
    x: float = math.nan
    y: float = math.nan
    latitude: float = math.nan
    longitude: float = math.nan
    timeout: float = 60.0
    tolerance: float = 1.0
    watch: str = ""

    def __post_init__(self) -> None:
        _finite("z", self.z)
        local = not (math.isnan(self.x) and math.isnan(self.y))
        geodetic = not (math.isnan(self.latitude) and math.isnan(self.longitude))
        if local == geodetic:
            raise ValueError("give either x and y (ENU m from home) or latitude and longitude")
        if local:
            _finite("x", self.x)
            _finite("y", self.y)
        else:
            _finite("latitude", self.latitude)
            _finite("longitude", self.longitude)
            if abs(self.latitude) > 90 or abs(self.longitude) > 180:
                raise ValueError(
                    f"({self.latitude}, {self.longitude}) is not a latitude and longitude"
                )
        _watch_key(self.watch)

    @property
    def geodetic(self) -> bool:
        return math.isnan(self.x)


class ReturnRequest(msgspec.Struct, kw_only=True, forbid_unknown_fields=True, frozen=True):
    """Fly home and land; done once on the ground and disarmed, within ``timeout`` s.
    ``watch`` as for :class:`GotoRequest`."""

    timeout: float = 180.0
    watch: str = ""

    def __post_init__(self) -> None:
        _watch_key(self.watch)


class MissionRequest(msgspec.Struct, kw_only=True, forbid_unknown_fields=True, frozen=True):
    """``start`` (fly the uploaded mission from its current item), ``pause`` (hold where the
    aircraft is) or ``resume`` (go on from where it paused); done once the aircraft flies
    it (or holds). ``watch`` as for :class:`GotoRequest` (a start's or resume's)."""

    action: str
    timeout: float = 10.0
    watch: str = ""

    def __post_init__(self) -> None:
        if self.action not in MISSION_ACTIONS:
            raise ValueError(
                f"action must be one of {', '.join(MISSION_ACTIONS)}, got {self.action!r}"
            )
        _watch_key(self.watch)


class CommanderBeat(msgspec.Struct, kw_only=True, frozen=True):
    """A commander's process is alive: sent about once a second while a go-to, return or
    mission it started may run unattended. ``key`` is the ``watch`` its requests name."""

    key: str
    stamp: float = 0.0  # Unix s, the sender's clock


def _watch_key(key: str) -> None:
    """A liveliness key of :data:`~dronewrapper.msgs.registry.ALIVE`'s shape, or ""."""
    if not isinstance(key, str) or len(key) > 200:
        raise ValueError("watch must be a string of at most 200 characters")
    parts = key.split("/")
    if key and (len(parts) != 3 or parts[1] != "alive" or not all(parts) or "*" in key):
        raise ValueError(f"watch must be a liveliness key {{ns}}/alive/{{name}}, got {key!r}")


class CancelRequest(msgspec.Struct, kw_only=True, forbid_unknown_fields=True, frozen=True):
    """End the running take-off, landing, go-to or return at once; the aircraft holds where it
    is.
    ``reason`` (for the log, at most 200 characters) says why."""

    reason: str = ""

    def __post_init__(self) -> None:
        if not isinstance(self.reason, str) or len(self.reason) > 200:
            raise ValueError("reason must be a string of at most 200 characters")


class FlightResult(msgspec.Struct, kw_only=True, frozen=True):
    """How a long action ended.

    Attributes:
        success: it ended where asked (or nothing was needed: ``message`` says so).
        failure: ``""`` or one of :data:`FAILURES`.
        step: the step that was refused (``set_mode OFFBOARD``, ``arming``, ``takeoff`` ...).
        result: that step's MAV_RESULT (-1: no answer), None when none applies.
        message: what happened, for a person.
        height: the height reached above the take-off point (m), NaN when unknown.
    """

    success: bool = False
    failure: str = ""
    step: str = ""
    result: int | None = None
    message: str = ""
    height: float = math.nan
