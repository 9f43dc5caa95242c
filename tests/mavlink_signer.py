"""A pymavlink encoder for a test's MAVLink peer, signing what it packs when given a key."""

from __future__ import annotations

import os
import time

os.environ.setdefault("MAVLINK20", "1")

from pymavlink.dialects.v20 import common as mavlink

from dronewrapper_sim.mavlink_io import signing_timestamp


def encoder(
    key: bytes | None,
    timestamp: int | None = None,
    *,
    system: int = 1,
    component: int = 1,
    link_id: int = 0,
) -> mavlink.MAVLink:
    """An encoder as ``system``/``component``; with ``key`` it signs every frame it packs on
    ``link_id``, its clock starting at ``timestamp`` (10 us units since 2015; None: now)."""
    mav = mavlink.MAVLink(None, srcSystem=system, srcComponent=component)
    if key is not None:
        mav.signing.secret_key = key
        mav.signing.sign_outgoing = True
        mav.signing.timestamp = signing_timestamp(time.time()) if timestamp is None else timestamp
        mav.signing.link_id = link_id
    return mav
