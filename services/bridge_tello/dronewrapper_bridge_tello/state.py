"""The Tello's state string (UDP 8890, 10 Hz) parsed into numbers, strictly.

Format (Tello SDK 2.0), ``key:value;`` pairs ending in ``\\r\\n``::

    mid:-1;x:0;y:0;z:0;mpry:0,0,0;pitch:0;roll:0;yaw:0;vgx:0;vgy:0;vgz:0;templ:60;temph:62;
    tof:10;h:0;bat:87;baro:120.52;time:0;agx:-1.00;agy:0.00;agz:-999.00;

Units as the drone sends them: degrees (pitch, roll, yaw), dm/s (vgx, vgy, vgz), cm (tof, h),
percent (bat), m (baro), s of motor time (time), cm/s^2 x 100... (agx, agy, agz as sent). Fields
this bridge needs must be present and finite; a datagram that is not a state string (binary,
missing fields, non-numbers) raises :class:`StateError` and changes nothing.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

REQUIRED = {
    "pitch": "pitch_deg",
    "roll": "roll_deg",
    "yaw": "yaw_deg",
    "vgx": "vgx",
    "vgy": "vgy",
    "vgz": "vgz",
    "tof": "tof_cm",
    "h": "h_cm",
    "bat": "battery_percent",
    "time": "motor_time_s",
}
"""The fields a state string must have, each with its :class:`TelloState` attribute."""
OPTIONAL = {
    "baro": "baro_m",
    "templ": "templ_c",
    "temph": "temph_c",
    "agx": "agx",
    "agy": "agy",
    "agz": "agz",
}
"""The fields a state string may have (NaN when absent or not a finite number)."""
MAX_DATAGRAM = 1024


class StateError(ValueError):
    """A datagram that is not a usable Tello state string; the message says why."""


@dataclass(frozen=True)
class TelloState:
    """One state string's numbers, in the drone's own units (see module docstring)."""

    pitch_deg: float
    roll_deg: float
    yaw_deg: float
    vgx: float  # dm/s
    vgy: float
    vgz: float
    tof_cm: float
    h_cm: float
    battery_percent: float
    motor_time_s: float
    baro_m: float = math.nan
    templ_c: float = math.nan
    temph_c: float = math.nan
    agx: float = math.nan
    agy: float = math.nan
    agz: float = math.nan


def _number(key: str, text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise StateError(f"field {key!r} is not a number: {text[:20]!r}") from None
    if not math.isfinite(value):
        raise StateError(f"field {key!r} is not finite: {text[:20]!r}")
    return value


def parse_fields(datagram: bytes) -> dict[str, str]:
    """The ``key:value`` pairs of a state datagram (raises StateError if it is not one)."""
    if len(datagram) > MAX_DATAGRAM:
        raise StateError(f"datagram of {len(datagram)} bytes is too long for a state string")
    try:
        text = datagram.decode("ascii")
    except UnicodeDecodeError:
        raise StateError("datagram is not ASCII text") from None
    fields: dict[str, str] = {}
    for part in text.strip().split(";"):
        part = part.strip()
        if not part:
            continue
        key, sep, value = part.partition(":")
        if not sep or not key:
            raise StateError(f"malformed field {part[:30]!r}")
        fields[key] = value
    return fields


def parse_state(datagram: bytes) -> TelloState:
    """Parse one state datagram (see module docstring)."""
    fields = parse_fields(datagram)
    missing = [k for k in REQUIRED if k not in fields]
    if missing:
        raise StateError(f"state string lacks {', '.join(missing)}")
    values = {k: _number(k, fields[k]) for k in REQUIRED}
    optional = {}
    for key in OPTIONAL:
        if key in fields:
            try:
                optional[key] = _number(key, fields[key])
            except StateError:
                optional[key] = math.nan  # an optional field never rejects the datagram
    if not 0.0 <= values["bat"] <= 100.0:
        raise StateError(f"bat {values['bat']:g} is not a percentage")
    for key in ("pitch", "roll", "yaw"):
        if abs(values[key]) > 360.0:
            raise StateError(f"{key} {values[key]:g} is not an angle in degrees")
    return TelloState(
        **{name: values[key] for key, name in REQUIRED.items()},
        **{name: optional.get(key, math.nan) for key, name in OPTIONAL.items()},
    )
