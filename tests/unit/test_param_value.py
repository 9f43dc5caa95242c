"""ParamValue: which field holds the value (issue 21: an integer parameter 0 came back as 0.0)."""

from __future__ import annotations

from dronewrapper.msgs import codec
from dronewrapper.msgs.mavros import PARAM_INTEGER, PARAM_REAL, ParamSet, ParamValue


def test_kind_says_which_field_holds_the_value():
    zero = ParamValue(integer=0, kind=PARAM_INTEGER).as_number()
    assert zero == 0 and isinstance(zero, int)
    real_zero = ParamValue(real=0.0, kind=PARAM_REAL).as_number()
    assert real_zero == 0.0 and isinstance(real_zero, float)
    assert ParamValue(integer=7, real=1.5, kind=PARAM_REAL).as_number() == 1.5


def test_without_kind_the_mavros_rule_applies():
    assert ParamValue(integer=3).as_number() == 3
    assert isinstance(ParamValue().as_number(), float)  # ambiguous zero: MAVROS's 0.0


def test_of_sets_the_kind_and_the_kind_survives_the_wire():
    assert ParamValue.of(0) == ParamValue(integer=0, kind=PARAM_INTEGER)
    assert ParamValue.of(2.5) == ParamValue(real=2.5, kind=PARAM_REAL)
    decoded = codec.decoder(ParamValue).decode(codec.encode(ParamValue.of(0)))
    assert decoded.as_number() == 0 and isinstance(decoded.as_number(), int)


def test_a_write_request_of_a_number_wraps_it_by_its_kind():
    assert ParamSet.of("SPEED", 50) == ParamSet(param_id="SPEED", value=ParamValue.of(50))
    assert ParamSet.of("WP_SPD", 7.5).value == ParamValue(real=7.5, kind=PARAM_REAL)
