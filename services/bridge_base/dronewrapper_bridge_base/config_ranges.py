"""Ranges the bridges' configs share, declared on the type (``msgspec.Meta``) so that a bad value
fails as the config is decoded, with its key, range and value named
(:mod:`dronewrapper.runtime.config_ranges`)."""

from __future__ import annotations

from typing import Annotated

import msgspec

StreamRate = Annotated[float, msgspec.Meta(ge=20)]
"""The setpoint stream's rate while commanded (Hz): the contract asks for 20 Hz at least."""
Attempts = Annotated[int, msgspec.Meta(ge=1)]
"""How many times a request is sent before giving up."""
LateSetpoint = Annotated[float, msgspec.Meta(gt=0, le=5)]
"""How much later than its peers' lag a setpoint is refused (s)."""
ComponentId = Annotated[int, msgspec.Meta(ge=0, le=255)]
"""A MAVLink system or component id (0: the first one heard)."""
Seconds60 = Annotated[float, msgspec.Meta(gt=0, le=60)]
"""A timeout or period of a minute at most (s)."""
Seconds30 = Annotated[float, msgspec.Meta(gt=0, le=30)]
"""A timeout or period of half a minute at most (s)."""
