"""What a page may ask: every field required, finite and in range; the config is strict."""

from __future__ import annotations

import math

import pytest

from dronewrapper.runtime.config import ConfigError, load_config
from dronewrapper_ground_station.config import Config, TeleopLimits
from dronewrapper_ground_station.requests import (
    BadRequest,
    goto,
    number,
    object_velocity,
    sticks,
    text,
)

LIMITS = TeleopLimits(horizontal=2.0, vertical=1.0, yaw_rate=0.5)
FULL = {"forward": 1.0, "left": -0.5, "up": 0.25, "turn": -1}


def test_sticks_scale_by_the_limits_in_flu() -> None:
    cmd = sticks(FULL, LIMITS)
    assert (cmd.vx, cmd.vy, cmd.vz, cmd.yaw_rate) == (2.0, -1.0, 0.25, -0.5)


@pytest.mark.parametrize(
    "bad",
    [
        {**FULL, "forward": 1.5},
        {**FULL, "left": math.nan},
        {**FULL, "up": math.inf},
        {**FULL, "turn": "1"},
        {**FULL, "turn": True},
        {**FULL, "forward": None},
        {k: v for k, v in FULL.items() if k != "up"},
        [1, 2, 3, 4],
        "forward",
    ],
)
def test_bad_sticks_are_refused(bad) -> None:
    with pytest.raises(BadRequest):
        sticks(bad, LIMITS)


def test_error_names_the_field() -> None:
    with pytest.raises(BadRequest, match="height is required"):
        number({}, "height", 0.5, 30)
    with pytest.raises(BadRequest, match=r"height must be finite and in \[0.5, 30\]"):
        number({"height": 31}, "height", 0.5, 30)


def test_goto_within_range() -> None:
    assert goto({"x": 3, "y": -4.5}, 100) == (3.0, -4.5)
    with pytest.raises(BadRequest, match="x must be"):
        goto({"x": 101, "y": 0}, 100)
    with pytest.raises(BadRequest, match="y is required"):
        goto({"x": 1}, 100)


def test_object_velocity() -> None:
    assert object_velocity({"east": 1, "north": -0.5}, 2.0) == (2.0, -1.0)
    with pytest.raises(BadRequest):
        object_velocity({"east": 2, "north": 0}, 2.0)


def test_text() -> None:
    assert text({"mode": " OFFBOARD "}, "mode") == "OFFBOARD"
    for bad in ({"mode": ""}, {"mode": 3}, {"mode": "x" * 65}, {"mode": "a\nb"}, {}):
        with pytest.raises(BadRequest, match="mode"):
            text(bad, "mode")


def test_config_defaults_are_loopback() -> None:
    config = load_config(Config)
    assert config.host == "127.0.0.1" and config.token == ""


@pytest.mark.parametrize(
    ("data", "key"),
    [
        ({"prot": 80}, "prot"),
        ({"port": 70000}, "port"),
        ({"teleop": {"horizontal": -1}}, "teleop.horizontal"),
        ({"teleop": {"timeout": math.nan}}, "teleop.timeout"),
        ({"teleop": {"speed": 1}}, "speed"),
        ({"namespaces": ["a/b"]}, "namespaces"),
        ({"token": "short"}, "token"),
        ({"telemetry_rate_hz": 0}, "telemetry_rate_hz"),
    ],
)
def test_config_errors_name_the_key(data, key: str) -> None:
    with pytest.raises(ConfigError, match=key):
        load_config(Config, data=data)
