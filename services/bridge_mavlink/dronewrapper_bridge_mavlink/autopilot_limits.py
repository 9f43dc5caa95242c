"""The autopilot's own return and fence behaviour, kept consistent with the envelope (pure).

The autopilot flies some things without the bridge: its return (RTL) climbs to its return
altitude first, and its fence fires its own action. Left at their defaults a breach "return"
climbs to PX4's 30 m (``RTL_RETURN_ALT``) above a 15 m ceiling, and a fence breach the
autopilot sees first holds instead of returning. So the bridge writes the autopilot's
parameters whenever the envelope or the autopilot changes (:func:`sync`, an operation):

- the return altitude: at most ``max_altitude - RETURN_ALT_BELOW_CEILING_M`` m above home
  (PX4 ``RTL_RETURN_ALT`` and ``RTL_DESCEND_ALT`` in m; ArduCopter 4.8 ``RTL_ALT_M`` in m, and
  ``RTL_ALT`` in cm before it: whichever the autopilot has, :data:`ONE_OF`), at
  least :data:`MIN_RETURN_ALT_M`; a lower value the autopilot holds is kept. A return then
  never climbs above the ceiling (it starts at the current height when that is higher, and a
  breach is declared before that is far above).
- ArduCopter's other return heights (:mod:`~dronewrapper_bridge_mavlink.rally_returns` has its
  rule): its final height over the destination ``RTL_ALT_FINAL_M`` at most the return altitude
  (a higher one climbs there at the end), the climb it adds to the height it starts at
  ``RTL_CLIMB_MIN_M`` at most 0, and ``RTL_ALT_TYPE`` 0 (heights above home, the envelope's
  frame; 1 would fly them above the terrain). Before 4.8: ``RTL_ALT_FINAL`` and
  ``RTL_CLIMB_MIN`` in cm. A rally point above the return altitude is refused
  (:func:`check_rally_returns`), at its upload and when a new envelope would put it there.
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
from collections.abc import Generator, Sequence
from typing import Protocol

from dronewrapper.envelope import Envelope
from dronewrapper.msgs.mavros import ParamSet, ParamValue
from dronewrapper.msgs.mission import EnvelopeSet, Waypoint
from dronewrapper.runtime import ServiceError
from dronewrapper_bridge_base.core_view import Stamped, Starting
from dronewrapper_bridge_mavlink import rally_returns
from dronewrapper_bridge_mavlink.config import Config
from dronewrapper_bridge_mavlink.mission_frames import MissionFrameError
from dronewrapper_bridge_mavlink.mission_state import Limits, MissionState
from dronewrapper_bridge_mavlink.modes import AUTOPILOT_ARDUPILOT, AUTOPILOT_PX4
from dronewrapper_bridge_mavlink.parameters import HasParameters

log = logging.getLogger("bridge_mavlink")

RETURN_ALT_BELOW_CEILING_M = 1.0
MIN_RETURN_ALT_M = 2.0
PX4_FENCE_ACTION = {"hold": 2, "return": 3, "land": 5}
ARDUPILOT_FENCE_ACTION = {"hold": 4, "return": 1, "land": 2}
AT_MOST = "at_most"  # lowered to the value when above it, else kept
EXACTLY = "exactly"
ONE_OF = (
    ("RTL_ALT_M", "RTL_ALT"),
    ("RTL_ALT_FINAL_M", "RTL_ALT_FINAL"),
    ("RTL_CLIMB_MIN_M", "RTL_CLIMB_MIN"),
)
"""Names of one setting across firmware versions (ArduCopter 4.8 renamed ``RTL_ALT``, in cm,
to ``RTL_ALT_M``, in m, and the others alike): the autopilot has one of them, the others are
not asked to change (and, once unanswered, not asked again of that autopilot)."""
INTEGER_PARAMS = frozenset({"RTL_ALT", "RTL_ALT_FINAL", "RTL_CLIMB_MIN"})
"""The ``AT_MOST`` parameters held as integers (the fence actions, ``EXACTLY``, are too)."""


class LimitsPort(Stamped, Starting, HasParameters, Protocol):
    """What keeping the autopilot's limits uses of the core besides its time, a background
    operation's start and its parameters: the autopilot as heard (kind, ``""`` before a
    heartbeat; connected), the configured envelope, the mission state (envelope, home, rally
    points, :class:`Limits`) and a bridge warning."""

    autopilot: str
    connected: bool
    config: Config
    missions: MissionState

    def bridge_text(self, text: str) -> None: ...


def return_altitude(envelope: Envelope) -> float:
    """The highest return altitude (m above home) under ``envelope``'s ceiling."""
    return max(MIN_RETURN_ALT_M, envelope.max_altitude - RETURN_ALT_BELOW_CEILING_M)


def px4_return_altitude(
    core: LimitsPort, envelope: Envelope | None = None
) -> Generator[float, None, float]:
    """The return altitude a PX4 return climbs to above its destination (m): its
    ``RTL_RETURN_ALT``, at most :func:`return_altitude` under ``envelope`` (default: the one
    in force; the bridge lowers it to that), that bound where the autopilot does not answer."""
    bound = return_altitude(envelope or core.missions.envelope)
    got = yield from core.parameters.read("RTL_RETURN_ALT")
    if got is None:
        return bound
    return min(bound, float(core.parameters.decode(*got).as_number()))


def check_rally_returns(
    core: LimitsPort, rally: Sequence[Waypoint], envelope: Envelope
) -> Generator[float, None, None]:
    """Refuse a rally point a return to it would climb too high from under ``envelope``
    (:func:`rally_returns.check`: PX4 with its ``RTL_RETURN_ALT``, ArduCopter with the return
    altitude the bridge keeps).

    Raises:
        MissionFrameError: naming the rally point.
    """
    ardupilot = core.autopilot == AUTOPILOT_ARDUPILOT
    if ardupilot:
        return_alt = return_altitude(envelope)
    else:
        return_alt = yield from px4_return_altitude(core, envelope)
    home = core.missions.home_geo
    rally_returns.check(rally, envelope, home, ardupilot=ardupilot, return_alt=return_alt)


def check_new_envelope(core: LimitsPort, request: EnvelopeSet) -> Generator[float, None, None]:
    """envelope/set's check: the rally points uploaded before stay within reach of a return
    under the envelope asked for (:func:`check_rally_returns`).

    Raises:
        ServiceError: (``refused``) naming the rally point.
    """
    new = core.config.envelope if request.reset else request.envelope
    if new is None or not core.missions.rally or not core.connected:
        return
    try:
        yield from check_rally_returns(core, core.missions.rally, new)
    except MissionFrameError as exc:
        raise ServiceError(f"envelope refused: {exc}", "refused") from None


def wanted(autopilot: str, envelope: Envelope) -> list[tuple[str, float, str]]:
    """The parameters to keep: (name, value, :data:`AT_MOST` or :data:`EXACTLY`)."""
    alt = return_altitude(envelope)
    if autopilot == AUTOPILOT_ARDUPILOT:
        centimetres = float(round(alt * 100.0))
        return [
            ("RTL_ALT_M", alt, AT_MOST),  # m, ArduCopter 4.8 on
            ("RTL_ALT", centimetres, AT_MOST),  # cm, before 4.8
            ("FENCE_ACTION", float(ARDUPILOT_FENCE_ACTION[envelope.breach_action]), EXACTLY),
            ("RTL_ALT_TYPE", 0.0, EXACTLY),  # above home, not above the terrain
            ("RTL_ALT_FINAL_M", alt, AT_MOST),
            ("RTL_ALT_FINAL", centimetres, AT_MOST),
            ("RTL_CLIMB_MIN_M", 0.0, AT_MOST),
            ("RTL_CLIMB_MIN", 0.0, AT_MOST),
        ]
    return [
        ("RTL_RETURN_ALT", alt, AT_MOST),
        ("RTL_DESCEND_ALT", alt, AT_MOST),
        ("GF_ACTION", float(PX4_FENCE_ACTION[envelope.breach_action]), EXACTLY),
    ]


def to_write(current: float | None, value: float, how: str) -> float | None:
    """The value to write over ``current`` (None: unknown), or None to leave it."""
    if how == EXACTLY:
        return None if current == value else value
    return None if current is not None and current <= value else value


def sync(core: LimitsPort) -> Generator[float, None, str]:
    """Keep :func:`wanted` unless already done for this autopilot and envelope (a value the
    autopilot holds lower than asked is kept); the problem ("" when all were taken)."""
    limits: Limits = core.missions.limits
    while limits.running:  # one writer at a time; the other waits for its result
        yield core.now + 0.05
    autopilot = core.autopilot or AUTOPILOT_PX4
    key = (autopilot, core.missions.envelope)
    if limits.written_for == key or not core.connected:
        return limits.problem
    limits.running = True
    try:
        problems, written, absent, answered = [], [], set(), set()
        alternatives = {name for names in ONE_OF for name in names}
        for name, value, how in wanted(autopilot, key[1]):
            if (autopilot, name) in limits.absent:
                absent.add(name)
                continue
            got = yield from core.parameters.read(name)
            if got is None and name in alternatives:
                absent.add(name)  # another firmware version's name: the other one is kept
                continue
            answered.add(name)
            current = None if got is None else core.parameters.decode(*got)
            number = None if current is None else float(current.as_number())
            write = to_write(number, value, how)
            if write is None:
                continue
            integer = how == EXACTLY or name in INTEGER_PARAMS
            param = ParamValue.of(int(write) if integer else write)
            reply = yield from core.parameters.set(ParamSet(param_id=name, value=param))
            if reply.success:
                written.append(f"{name}={write:g}")
            else:
                problems.append(f"{name}={write:g}: {reply.message}")
        asked = {name for name, _, _ in wanted(autopilot, key[1])}
        for names in ONE_OF:
            if asked & set(names) and asked & set(names) <= absent:
                problems.append(f"{' / '.join(names)}: no such parameter answered")
            elif answered & set(names):  # this firmware's name known: the others not asked again
                limits.absent |= {(autopilot, name) for name in absent & set(names)}
        limits.problem = "; ".join(problems)
        limits.written_for = key
    finally:
        limits.running = False
    if limits.problem:
        text = f"the autopilot's return or fence may leave the envelope: {limits.problem}"
        core.bridge_text(text)
    elif written:
        log.info("autopilot return and fence set for the envelope: %s", ", ".join(written))
    return limits.problem


def settled(core: LimitsPort, seconds: float) -> Generator[float, None, bool]:
    """Wait up to ``seconds`` for the limits to be kept for this autopilot and envelope (a
    :func:`sync` started in the background when none runs); whether they are."""
    limits: Limits = core.missions.limits
    key = (core.autopilot or AUTOPILOT_PX4, core.missions.envelope)
    if limits.written_for == key:
        return True
    if not limits.running:
        core.start(sync_steps(core), core.now, core.stamp, background=True)
    deadline = core.now + seconds
    while limits.written_for != key and core.now < deadline:
        yield min(deadline, core.now + 0.05)
    return limits.written_for == key


def sync_steps(core: LimitsPort) -> Generator[float, None, str]:
    """:func:`sync` as a background operation (the core starts it on connect and on a new
    envelope)."""
    return (yield from sync(core))


__all__ = [
    "ONE_OF",
    "Limits",
    "LimitsPort",
    "check_new_envelope",
    "check_rally_returns",
    "return_altitude",
    "settled",
    "sync",
    "to_write",
    "wanted",
]
