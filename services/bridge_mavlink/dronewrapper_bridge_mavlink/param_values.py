"""Parameter values on the wire (pure): what a ParamSet may write, and how it is encoded.

MAVLink carries every parameter value in a float32 field (PARAM_SET.param_value). Real
parameters (MAV_PARAM_TYPE_REAL32) hold the value itself; integer parameters are either the
int32's bytes reinterpreted as a float (PX4, "bytewise") or the integer converted to a float
(ArduPilot, "C cast", exact up to 2**24). A request is refused, naming the field, when the value
cannot be represented exactly enough on the parameter's type: never written rounded, wrapped or
overflowed (an ``integer`` of 2**64-1 on a float parameter must not write 1.8e19).
"""

from __future__ import annotations

import math
import struct

from pymavlink.dialects.v20 import common as mavlink
from pymavlink.dialects.v20.common import MAV_PARAM_TYPE_REAL32

from dronewrapper.msgs.mavros import PARAM_INTEGER, PARAM_REAL, ParamValue

INTEGER_RANGES = {  # MAV_PARAM_TYPE -> (min, max) it can hold
    mavlink.MAV_PARAM_TYPE_UINT8: (0, 2**8 - 1),
    mavlink.MAV_PARAM_TYPE_INT8: (-(2**7), 2**7 - 1),
    mavlink.MAV_PARAM_TYPE_UINT16: (0, 2**16 - 1),
    mavlink.MAV_PARAM_TYPE_INT16: (-(2**15), 2**15 - 1),
    mavlink.MAV_PARAM_TYPE_UINT32: (0, 2**32 - 1),
    mavlink.MAV_PARAM_TYPE_INT32: (-(2**31), 2**31 - 1),
}
INTEGER_PARAM_TYPES = frozenset(INTEGER_RANGES)  # UINT8 .. INT32
FLOAT32_MAX = 3.4028234663852886e38
FLOAT32_EXACT_INT = 2**24  # every integer up to this magnitude is exact in a float32
ARDUPILOT_EXACT_INT = FLOAT32_EXACT_INT  # ArduPilot sends integers as float values


def float_bits_to_int(value: float) -> int:
    """The int32 whose bytes are those of float32 ``value`` (PX4's integer encoding)."""
    return struct.unpack("<i", struct.pack("<f", value))[0]


def int_to_float_bits(value: int) -> float:
    """The float32 whose bytes are those of int32 ``value`` (PX4's integer encoding)."""
    return struct.unpack("<f", struct.pack("<i", value))[0]


def requested_number(param_id: str, value: ParamValue) -> int | float:
    """The one number a ParamValue asks for: ``integer`` when non-zero, else ``real``.

    Raises:
        ValueError: both are set and disagree, or ``real`` is not finite (names the field).
    """
    if not math.isfinite(value.real):
        raise ValueError(f"{param_id}: value.real must be finite, got {value.real!r}")
    if value.integer != 0 and value.real != 0.0 and float(value.integer) != value.real:
        raise ValueError(
            f"{param_id}: value.integer={value.integer} and value.real={value.real!r} disagree "
            f"(set one of them)"
        )
    return value.integer if value.integer != 0 else value.real


def encode_param(param_id: str, value: ParamValue, param_type: int, *, bytewise: bool) -> float:
    """The float32 PARAM_SET.param_value writing ``value`` to a parameter of ``param_type``.

    Args:
        param_id: the parameter's name (for error messages).
        value: the request's value.
        param_type: MAV_PARAM_TYPE the autopilot reported for the parameter.
        bytewise: integers travel as their bytes (PX4) rather than as a float value.

    Raises:
        ValueError: the value does not fit the parameter's type; the message names the field,
            the parameter and the allowed range.
    """
    number = requested_number(param_id, value)
    field = "value.integer" if value.integer != 0 else "value.real"
    if param_type in INTEGER_PARAM_TYPES:
        if isinstance(number, float) and number != int(number):
            raise ValueError(f"{param_id} is an integer parameter, got {field}={number!r}")
        wanted = int(number)
        low, high = INTEGER_RANGES[param_type]
        if not bytewise:
            low, high = max(low, -ARDUPILOT_EXACT_INT), min(high, ARDUPILOT_EXACT_INT)
        if not low <= wanted <= high:
            raise ValueError(f"{param_id}: {field}={wanted} outside [{low}, {high}] of its type")
        if bytewise:
            return int_to_float_bits(wanted if wanted < 2**31 else wanted - 2**32)
        return float(wanted)
    if param_type != MAV_PARAM_TYPE_REAL32:
        raise ValueError(f"{param_id}: parameter type {param_type} cannot be written")
    if isinstance(number, int) and abs(number) > FLOAT32_EXACT_INT:
        raise ValueError(
            f"{param_id} is a float32 parameter: {field}={number} is not exact in float32 "
            f"(|integer| <= {FLOAT32_EXACT_INT}; use value.real)"
        )
    real = float(number)
    if abs(real) > FLOAT32_MAX:
        raise ValueError(f"{param_id}: {field}={real!r} is beyond the float32 range (±3.4e38)")
    return real


def decode_param(raw: float, param_type: int, *, bytewise: bool) -> ParamValue:
    """The ParamValue of a PARAM_VALUE's ``raw`` float for a parameter of ``param_type``."""
    if param_type in INTEGER_PARAM_TYPES:
        if bytewise:
            return ParamValue(integer=float_bits_to_int(raw), kind=PARAM_INTEGER)
        if not math.isfinite(raw):
            return ParamValue()
        return ParamValue(integer=int(raw), kind=PARAM_INTEGER)
    return ParamValue(real=raw, kind=PARAM_REAL)
