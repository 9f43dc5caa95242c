"""param/set values are checked against the parameter's type before anything is written."""

from __future__ import annotations

import math

import pytest

from dronewrapper.msgs.mavros import ParamValue
from dronewrapper_bridge_mavlink.param_values import (
    MAV_PARAM_TYPE_REAL32,
    decode_param,
    encode_param,
    float_bits_to_int,
)

INT32 = 6
UINT8 = 1


def test_a_huge_integer_on_a_float_parameter_is_refused_naming_the_field():
    # issue 12: integer 2**64-1 wrote 1.8e19 into RTL_LAND_DELAY
    with pytest.raises(ValueError, match=r"RTL_LAND_DELAY .*value\.integer=18446744073709551615"):
        encode_param(
            "RTL_LAND_DELAY", ParamValue(integer=2**64 - 1), MAV_PARAM_TYPE_REAL32, bytewise=True
        )


def test_a_real_beyond_float32_is_a_bad_request_not_an_internal_error():
    with pytest.raises(ValueError, match=r"value\.real=1e\+39 is beyond the float32 range"):
        encode_param("MPC_XY_VEL_MAX", ParamValue(real=1e39), MAV_PARAM_TYPE_REAL32, bytewise=True)


@pytest.mark.parametrize("real", [math.nan, math.inf, -math.inf])
def test_non_finite_reals_are_refused(real):
    with pytest.raises(ValueError, match=r"value\.real must be finite"):
        encode_param("X", ParamValue(real=real), MAV_PARAM_TYPE_REAL32, bytewise=True)


def test_integer_and_real_that_disagree_are_refused():
    with pytest.raises(ValueError, match="disagree"):
        encode_param("X", ParamValue(integer=3, real=4.0), MAV_PARAM_TYPE_REAL32, bytewise=True)
    assert encode_param("X", ParamValue(integer=3, real=3.0), INT32, bytewise=False) == 3.0


@pytest.mark.parametrize(
    ("value", "param_type", "bytewise", "match"),
    [
        (ParamValue(integer=2**31), INT32, True, r"value\.integer=2147483648 outside"),
        (ParamValue(integer=256), UINT8, True, r"outside \[0, 255\]"),
        (ParamValue(integer=-1), UINT8, True, r"outside \[0, 255\]"),
        (ParamValue(real=2.5), INT32, True, r"integer parameter, got value\.real=2\.5"),
        (ParamValue(integer=2**24 + 1), INT32, False, "outside"),  # ArduPilot: float-exact only
        (ParamValue(integer=1), 10, True, "type 10 cannot be written"),
    ],
)
def test_integer_parameters_take_only_what_their_type_holds(value, param_type, bytewise, match):
    with pytest.raises(ValueError, match=match):
        encode_param("P", value, param_type, bytewise=bytewise)


def test_encodings_round_trip():
    raw = encode_param("COM_RC_IN_MODE", ParamValue(integer=4), INT32, bytewise=True)
    assert float_bits_to_int(raw) == 4
    assert decode_param(raw, INT32, bytewise=True).integer == 4
    assert encode_param("COM_RC_IN_MODE", ParamValue(real=4.0), INT32, bytewise=True) == raw
    assert encode_param("P", ParamValue(integer=-7), INT32, bytewise=False) == -7.0
    assert decode_param(-7.0, INT32, bytewise=False).integer == -7
    assert encode_param("P", ParamValue(integer=12), MAV_PARAM_TYPE_REAL32, bytewise=True) == 12.0
    assert decode_param(1.5, MAV_PARAM_TYPE_REAL32, bytewise=True).real == 1.5
    assert decode_param(math.nan, INT32, bytewise=False) == ParamValue()
