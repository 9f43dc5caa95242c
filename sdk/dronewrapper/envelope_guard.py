"""A DroneWrapper's envelope: the bridge's safety envelope, held and checked before sending.

``envelope()``, ``set_envelope(max_altitude=..., max_distance=..., fence=...)`` and
``reset_envelope()`` ask the bridge (``{ns}/dronewrapper/envelope/set``), which enforces its
envelope on every setpoint, take-off and mission item and uploads it to the autopilot as its
fence (fence: ``[(x, y), ...]`` ENU m from home). The envelope in force is held (as the bridge
publishes it, and as each reply gives it), so a setpoint, take-off or go-to outside it raises
:class:`~dronewrapper.errors.CommandRefused` naming the limit before anything is sent; nothing
held, the bridge judges alone and its refusal arrives on ``refusals``. Home (what the bridge
publishes on ``home_position/home``) is the origin of the envelope's positions.
"""

from __future__ import annotations

import logging
from typing import Any

import msgspec

from dronewrapper import envelope as env
from dronewrapper.client import DroneClient
from dronewrapper.commands import Commands
from dronewrapper.envelope import Envelope, EnvelopeError
from dronewrapper.errors import CommandRefused, DroneError, InvalidArgument, NoData
from dronewrapper.msgs import registry
from dronewrapper.msgs.mavros import MASK_MIXED, MASK_POSITION, PositionTarget
from dronewrapper.msgs.mission import EnvelopeResult, EnvelopeSet, HomePosition
from dronewrapper.runtime.latest import Latest

log = logging.getLogger("dronewrapper")


class EnvelopeGuard:
    """The bridge's envelope and home, held, and the checks against them (see the module doc);
    a part a DroneWrapper owns.

    Args:
        client: the drone client (its input holders: ``envelope``, ``home_position/home``).
        commands: the drone's service calls.
    """

    def __init__(self, client: DroneClient, commands: Commands) -> None:
        self.ns = client.ns
        self.commands = commands
        self.home_holder: Latest[HomePosition] = client.inputs.latest(registry.HOME_POSITION)
        self.held: Latest[Envelope] = client.inputs.latest(registry.ENVELOPE)

    def envelope(self, *, timeout: float | None = None) -> Envelope:
        """The envelope the bridge enforces now."""
        return self._call(EnvelopeSet(), "envelope", timeout).envelope

    def set_envelope(self, *, timeout: float | None = None, **limits: Any) -> Envelope:
        """Change the bridge's envelope: any of ``max_altitude`` (m above home, at least
        :data:`~dronewrapper.envelope.MIN_ALTITUDE_M`), ``max_distance`` (m from home),
        ``fence`` (``[(x, y), ...]`` ENU m from home; ``[]`` none; it must contain home or
        the drone), ``exclusions``, ``max_horizontal_speed``, ``max_vertical_speed`` (m/s),
        ``breach_action`` (``hold``, ``return``, ``land``), ``margin`` (m). The others stay.
        Returns the envelope in force. The new envelope outlives this program: the next one
        is warned on connect, and :meth:`reset_envelope` puts the bridge's configured one back.

        Raises:
            InvalidArgument: an unknown field, or a value of the wrong type or out of range (the
                message names the field; nothing is changed).
            CommandRefused: the bridge refused it (a fence containing neither home nor the
                drone).
        """
        current = self.envelope(timeout=timeout)
        unknown = set(limits) - set(Envelope.__struct_fields__)
        if unknown:
            raise InvalidArgument(f"set_envelope: unknown field(s) {sorted(unknown)}")
        fields = {**msgspec.structs.asdict(current), **limits}
        try:
            wanted = msgspec.convert(fields, Envelope)
        except msgspec.ValidationError as exc:
            raise InvalidArgument(f"set_envelope: {_named(exc)}") from None
        return self._call(EnvelopeSet(envelope=wanted), "set_envelope", timeout).envelope

    def reset_envelope(self, *, timeout: float | None = None) -> Envelope:
        """Put the bridge's configured envelope back (undo every :meth:`set_envelope`);
        returns it."""
        return self._call(EnvelopeSet(reset=True), "reset_envelope", timeout).envelope

    def put(self, envelope: Envelope, what: str, timeout: float | None) -> None:
        """Make ``envelope`` the bridge's (a mission's fence folded in, or put back)."""
        self._call(EnvelopeSet(envelope=envelope), what, timeout)

    def _call(self, request: EnvelopeSet, what: str, timeout: float | None) -> EnvelopeResult:
        """One envelope/set call; the envelope in force is then held for the setpoint checks."""
        reply = self.commands.command(registry.ENVELOPE_SET, request, what, timeout)
        self.held.update(reply.envelope)
        return reply

    def warn_if_commanded(self, timeout: float) -> None:
        """On connect: fetch the envelope in force (held for the setpoint checks) and warn when
        a commander set it rather than the bridge's configuration (it outlived its program)."""
        try:
            reply = self._call(EnvelopeSet(), "envelope", timeout)
        except DroneError:
            return  # a bridge without an envelope service: it judges alone
        if reply.set_by:
            e = reply.envelope
            fence = f"a fence of {len(e.fence)} vertices" if e.fence else "no fence"
            log.warning(
                "%s: the envelope in force was set by %r, not the bridge's configuration: "
                "max_altitude %g m, max_distance %g m, %s, breach_action %s; "
                "reset_envelope() puts the configured one back",
                self.ns,
                reply.set_by,
                e.max_altitude,
                e.max_distance,
                fence,
                e.breach_action,
            )

    def check_setpoint(self, target: PositionTarget, what: str) -> None:
        """CommandRefused, the limit named, when ``target`` is outside the envelope held (the
        bridge would refuse it); a position needs home too. Nothing held: the bridge judges,
        and its refusal arrives on ``refusals``."""
        envelope, home = self.held.value, self.home_holder.value
        if envelope is None:
            return
        try:
            if target.type_mask != MASK_POSITION:
                v = target.velocity
                env.check_velocity(envelope, v.x, v.y, v.z)
            if target.type_mask == MASK_POSITION and home is not None:
                p = target.required_position()
                env.check_position(envelope, p.x - home.x, p.y - home.y, p.z - home.z)
            elif target.type_mask == MASK_MIXED and home is not None:
                z = target.required_position().z - home.z  # its altitude only
                ceiling = envelope.max_altitude
                if z > ceiling:
                    reason = f"altitude {z:g} m above the envelope's {ceiling:g} m"
                    raise EnvelopeError(reason, "max_altitude")
        except EnvelopeError as exc:
            raise CommandRefused(what, f"outside the envelope: {exc}", limit=exc.limit) from None

    def held_or_asked(self, timeout: float) -> Envelope | None:
        """The bridge's envelope as last published, else asked for (None: no envelope service)."""
        envelope = self.held.value
        if envelope is None:
            try:
                envelope = self.envelope(timeout=timeout)
            except DroneError:
                return None
        return envelope

    def check_takeoff(self, h: float, timeout: float) -> None:
        """CommandRefused when a take-off to ``h`` m climbs above the bridge's envelope (the
        bridge refuses it too; this names the limit before anything is streamed)."""
        envelope = self.held_or_asked(timeout)
        if envelope is None:
            return  # a bridge without an envelope service: it judges alone
        try:
            env.check_takeoff(envelope, h)
        except EnvelopeError as exc:
            raise CommandRefused("takeoff", str(exc), limit=exc.limit) from None

    def check_goto(self, x: float, y: float, z: float, timeout: float) -> None:
        """CommandRefused when (x, y, z) ENU m from home is outside the bridge's envelope."""
        envelope = self.held_or_asked(timeout)
        if envelope is None:
            return
        try:
            env.check_position(envelope, x, y, z)
        except EnvelopeError as exc:
            raise CommandRefused("goto", str(exc), limit=exc.limit) from None

    def home(self) -> HomePosition:
        """Home as the bridge last published it: ``latitude``, ``longitude`` (degrees; NaN
        without GPS), ``altitude`` (m AMSL) and ``x``, ``y``, ``z`` in the local frame (the one
        of get_position). It is the origin of goto_local, goto's altitude and local missions.

        Raises:
            NoData: no home published yet.
        """
        home = self.home_holder.value
        if home is None:
            raise NoData(f"no home position yet on {registry.HOME_POSITION.key(self.ns)}")
        return home


def _named(exc: msgspec.ValidationError) -> str:
    """msgspec's message with the field first: ``max_altitude: Expected `float`, got `str```."""
    message, _, path = str(exc).partition(" - at `$.")
    return f"{path.rstrip('`')}: {message}" if path else message
