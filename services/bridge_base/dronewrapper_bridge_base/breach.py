"""The bridges' envelope rules about the aircraft itself (ENU m in the home frame).

* :func:`breach`: the aircraft's own position is outside the envelope by more than its
  ``margin`` (wind, a mission, a pilot): the bridge then takes ``breach_action`` (hold,
  return or land); :class:`BreachMonitor` declares it once per excursion.
* :func:`check_replacement`: a new envelope whose fence contains neither home nor the aircraft
  is refused (it would breach at once, or leave home outside: a return could never end).

The checks of a target (shared with the SDK) are :mod:`dronewrapper.envelope`.
"""

from __future__ import annotations

from dronewrapper.envelope import EnvelopeError, inside, violated, violation
from dronewrapper.msgs.envelope import Envelope


def check_replacement(envelope: Envelope, aircraft: tuple[float, float] | None) -> None:
    """EnvelopeError (limit ``fence``) when ``envelope``'s fence contains neither home (the
    origin) nor the aircraft at ``aircraft`` (x, y ENU m from home; None: not known)."""
    if not envelope.fence or inside(envelope.fence, 0.0, 0.0):
        return
    if aircraft is not None and inside(envelope.fence, *aircraft):
        return
    where = "" if aircraft is None else f" nor the aircraft at ({aircraft[0]:g}, {aircraft[1]:g}) m"
    raise EnvelopeError(f"the fence contains neither home{where}", "fence")


def breach(envelope: Envelope, x: float, y: float, z: float) -> str:
    """The limit the aircraft at (x, y, z) (ENU m from home) has crossed by more than the
    envelope's margin, or "" while it is inside."""
    return violation(envelope, x, y, z, envelope.margin)


class BreachMonitor:
    """Declares a breach once per excursion: :meth:`update` returns the reason the first time
    the aircraft is found outside, and again only after it has been back inside."""

    def __init__(self) -> None:
        self.outside = False
        self.breaches = 0
        self.limit = ""  # the envelope's field the last breach crossed

    def update(self, envelope: Envelope, position: tuple[float, float, float]) -> str:
        """The breach to act on now ("" when none or already acted on)."""
        limit, reason = violated(envelope, *position, envelope.margin)
        if not reason:
            if self.outside and not violation(envelope, *position):
                self.outside = False
            return ""
        if self.outside:
            return ""
        self.outside = True
        self.breaches += 1
        self.limit = limit
        return reason


__all__ = ["BreachMonitor", "breach", "check_replacement"]
