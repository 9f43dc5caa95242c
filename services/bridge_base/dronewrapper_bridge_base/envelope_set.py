"""The ``{ns}/dronewrapper/envelope/set`` request applied to a bridge's envelope (pure).

Every bridge keeps its envelope in force and who set it (``set_by``: the commander whose request put
it there; ``""``: the bridge's configured one). :func:`apply` reads, replaces or resets it: a
replacement whose fence contains neither home nor the aircraft is refused
(:func:`dronewrapper_bridge_base.breach.check_replacement`); a reset puts the configured envelope
back. The envelope is not reset when its commander goes: the SDK warns on connect that an envelope
set by a commander is in force (docs/api.md), and ``reset_envelope()`` puts the configured one back.
"""

from __future__ import annotations

from typing import Protocol

from dronewrapper.envelope import Envelope, EnvelopeError
from dronewrapper.msgs.mission import EnvelopeResult, EnvelopeSet
from dronewrapper.runtime.errors import ServiceError
from dronewrapper_bridge_base.breach import BreachMonitor, check_replacement


class EnvelopeHolder(Protocol):
    """What a bridge's mission state holds of its envelope."""

    envelope: Envelope
    monitor: BreachMonitor
    set_by: str


def apply(
    state: EnvelopeHolder,
    request: EnvelopeSet,
    *,
    configured: Envelope,
    caller: str,
    aircraft: tuple[float, float] | None,
) -> bool:
    """Apply ``request`` from ``caller`` to ``state``; True when the envelope changed.
    ``aircraft``: where it is now (x, y ENU m from home; None: not known).

    Raises:
        ServiceError: (code ``refused``) the new fence contains neither home nor the aircraft.
    """
    if request.reset:
        new, by = configured, ""
    elif request.envelope is not None:
        try:
            check_replacement(request.envelope, aircraft)
        except EnvelopeError as exc:
            raise ServiceError(f"envelope refused: {exc}", "refused") from None
        new, by = request.envelope, caller
    else:
        return False
    state.envelope, state.monitor, state.set_by = new, BreachMonitor(), by
    return True


def result(state: EnvelopeHolder) -> EnvelopeResult:
    """The reply: the envelope in force and who set it."""
    message = f"envelope set by {state.set_by!r} in force" if state.set_by else "envelope in force"
    return EnvelopeResult(
        success=True, message=message, envelope=state.envelope, set_by=state.set_by
    )
