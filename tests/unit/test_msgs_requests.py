"""Service requests are strict: no default that could actuate, unknown fields named, ranges."""

from __future__ import annotations

import math

import msgspec
import pytest

from dronewrapper.msgs import codec
from dronewrapper.msgs.mavros import (
    CommandBool,
    CommandTOL,
    ParamGet,
    ParamSet,
    PositionTarget,
    SetMode,
)


def decode(msg_type, fields: dict):
    return codec.decode(msg_type, msgspec.msgpack.encode(fields))


@pytest.mark.parametrize(
    ("msg_type", "missing"),
    [
        (CommandBool, "value"),
        (CommandTOL, "min_pitch"),
        (SetMode, "custom_mode"),
        (ParamGet, "param_id"),
        (ParamSet, "param_id"),
    ],
)
def test_an_empty_request_is_refused_naming_the_missing_field(msg_type, missing):
    with pytest.raises(msgspec.ValidationError, match=f"missing required field `{missing}`"):
        decode(msg_type, {})


def test_an_empty_arming_request_never_decodes_to_arm():
    with pytest.raises(msgspec.ValidationError, match="value"):
        decode(CommandBool, {})
    with pytest.raises(msgspec.ValidationError, match="Expected `bool`"):
        decode(CommandBool, {"value": 1})  # no truthy guessing
    assert decode(CommandBool, {"value": False}).value is False


def test_a_take_off_request_needs_every_field():
    full = msgspec.to_builtins(CommandTOL.takeoff(3.0))
    for name in full:
        partial = {k: v for k, v in full.items() if k != name}
        with pytest.raises(msgspec.ValidationError, match=f"`{name}`"):
            decode(CommandTOL, partial)
    assert decode(CommandTOL, full).altitude == 3.0


@pytest.mark.parametrize(
    ("msg_type", "fields"),
    [
        (CommandBool, {"value": False, "force": True}),
        (CommandTOL, {**msgspec.to_builtins(CommandTOL.land()), "altitdue": 3.0}),
        (SetMode, {"custom_mode": "OFFBOARD", "force": True}),
        (ParamGet, {"param_id": "X", "extra": 1}),
        (ParamSet, {"param_id": "X", "value": {"integer": 1, "real": 0.0, "force": 1}}),
    ],
)
def test_unknown_fields_are_refused_by_name(msg_type, fields):
    with pytest.raises(msgspec.ValidationError, match="unknown field"):
        decode(msg_type, fields)


@pytest.mark.parametrize(
    ("field", "value"),
    [
        ("min_pitch", math.nan),
        ("min_pitch", math.inf),
        ("min_pitch", 91.0),
        ("yaw", math.inf),
        ("latitude", 91.0),
        ("longitude", -math.inf),
        ("altitude", 1e300),
    ],
)
def test_take_off_and_land_fields_are_finite_and_in_range(field, value):
    fields = {**msgspec.to_builtins(CommandTOL.takeoff(2.0)), field: value}
    with pytest.raises(msgspec.ValidationError, match=f"CommandTOL.{field}"):
        decode(CommandTOL, fields)
    with pytest.raises(ValueError, match=f"CommandTOL.{field}"):
        CommandTOL(**fields)


def test_nan_means_here_and_default():
    land = decode(CommandTOL, msgspec.to_builtins(CommandTOL.land()))
    assert math.isnan(land.latitude) and math.isnan(land.longitude) and land.min_pitch == 0.0
    takeoff = CommandTOL.takeoff()
    assert math.isnan(takeoff.altitude) and math.isnan(takeoff.yaw)


def test_set_mode_and_param_set_ranges():
    with pytest.raises(msgspec.ValidationError, match=r"SetMode\.custom_mode"):
        decode(SetMode, {"custom_mode": ""})
    with pytest.raises(msgspec.ValidationError, match=r"SetMode\.base_mode"):
        decode(SetMode, {"custom_mode": "OFFBOARD", "base_mode": 81})
    with pytest.raises(msgspec.ValidationError, match=r"ParamSet\.value\.real"):
        decode(ParamSet, {"param_id": "X", "value": {"integer": 0, "real": math.inf}})
    with pytest.raises(msgspec.ValidationError, match="value"):
        decode(ParamSet, {"param_id": "X"})


def test_an_empty_setpoint_is_not_a_position_target_at_the_origin():
    with pytest.raises(msgspec.ValidationError, match="missing required field `coordinate_frame`"):
        decode(PositionTarget, {})
    with pytest.raises(msgspec.ValidationError, match="missing required field `type_mask`"):
        decode(PositionTarget, {"coordinate_frame": 1})
