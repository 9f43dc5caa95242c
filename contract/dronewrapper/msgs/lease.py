"""The command lease service's messages (see :mod:`dronewrapper_bridge_base.commander_lease`)."""

from __future__ import annotations

import msgspec


class LeaseRequest(msgspec.Struct, kw_only=True, forbid_unknown_fields=True, frozen=True):
    """Take, or give back, the command lease of one drone.

    The commander is the request's ``commander`` attachment (the SDK's name), not a field.
    ``action``: ``take`` (only if free or already ours), ``take_over`` (whoever holds it; logged
    and shown on State) or ``release``.
    """

    action: str = "take"


class LeaseReply(msgspec.Struct, kw_only=True, frozen=True):
    """``granted`` iff the action was done; ``holder`` is the commander holding it now."""

    granted: bool = False
    holder: str = ""
    previous: str = ""
    message: str = ""
