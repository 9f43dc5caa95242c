"""The safety envelope's rules (dronewrapper/envelope.py): each one refuses with its limit named."""

from __future__ import annotations

import math

import msgspec
import pytest

from dronewrapper.envelope import (
    Envelope,
    EnvelopeError,
    check_position,
    check_takeoff,
    check_velocity,
    distance_outside,
    inside,
)
from dronewrapper_bridge_base.breach import BreachMonitor, breach

SQUARE = [(-10.0, -10.0), (10.0, -10.0), (10.0, 10.0), (-10.0, 10.0)]


def test_defaults_are_those_a_real_aircraft_can_live_with():
    env = Envelope()
    assert (env.max_altitude, env.max_distance, env.breach_action) == (120.0, 500.0, "return")


def test_altitude_above_the_ceiling_is_refused_with_the_limit_named():
    with pytest.raises(EnvelopeError, match="altitude 500 m above the envelope's 120 m"):
        check_position(Envelope(), 0, 0, 500)
    check_position(Envelope(), 0, 0, 120)


def test_takeoff_above_the_ceiling_is_refused():
    with pytest.raises(EnvelopeError, match="take-off altitude 500 m above the envelope's 120 m"):
        check_takeoff(Envelope(), 500)
    check_takeoff(Envelope(), 120)
    check_takeoff(Envelope(), math.nan)  # the autopilot's default height


def test_distance_from_home_is_refused():
    with pytest.raises(EnvelopeError, match="distance 600 m from home beyond the envelope's 500"):
        check_position(Envelope(), 600, 0, 10)
    check_position(Envelope(), 300, 400, 10)  # 500 m exactly


def test_fence_polygon_refuses_outside_and_accepts_inside():
    env = Envelope(fence=SQUARE)
    check_position(env, 9, -9, 5)
    with pytest.raises(EnvelopeError, match="outside the envelope's fence"):
        check_position(env, 11, 0, 5)


def test_exclusion_zone_refuses_inside():
    env = Envelope(exclusions=[[(0.0, 0.0), (2.0, 0.0), (2.0, 2.0), (0.0, 2.0)]])
    with pytest.raises(EnvelopeError, match="exclusion zone 1"):
        check_position(env, 1, 1, 5)
    check_position(env, 3, 1, 5)


def test_speeds_beyond_the_maximum_are_refused():
    env = Envelope(max_horizontal_speed=5, max_vertical_speed=2)
    with pytest.raises(EnvelopeError, match=r"horizontal speed 5\.0990\d m/s above"):
        check_velocity(env, 5, 1, 0)
    with pytest.raises(EnvelopeError, match="vertical speed 3 m/s above the envelope's 2 m/s"):
        check_velocity(env, 0, 0, -3)
    check_velocity(env, 3, 4, 2)


def test_breach_allows_the_margin_then_names_the_limit():
    env = Envelope(max_altitude=10, margin=1.0)
    assert breach(env, 0, 0, 10.9) == ""
    assert "altitude" in breach(env, 0, 0, 11.2)
    fenced = Envelope(fence=SQUARE, margin=0.5)
    assert breach(fenced, 10.4, 0, 5) == ""
    assert "fence" in breach(fenced, 10.6, 0, 5)


def test_breach_monitor_acts_once_per_excursion():
    env = Envelope(max_distance=10, margin=0.0)
    monitor = BreachMonitor()
    assert monitor.update(env, (5, 0, 1)) == ""
    assert "distance" in monitor.update(env, (11, 0, 1))
    assert monitor.update(env, (12, 0, 1)) == ""  # still the same excursion
    assert monitor.update(env, (9, 0, 1)) == ""  # back inside
    assert "distance" in monitor.update(env, (11, 0, 1))
    assert monitor.breaches == 2


def test_breach_monitor_rearms_only_back_inside_the_envelope_not_within_its_margin():
    env = Envelope(max_altitude=10, margin=1.0)
    monitor = BreachMonitor()
    assert "altitude" in monitor.update(env, (0, 0, 11.5))  # beyond the margin: a breach
    assert monitor.update(env, (0, 0, 10.5)) == ""  # back within the margin, still outside
    assert monitor.update(env, (0, 0, 11.5)) == ""  # out again: the same excursion
    assert monitor.breaches == 1
    assert monitor.update(env, (0, 0, 9.5)) == ""  # inside the envelope: re-armed
    assert "altitude" in monitor.update(env, (0, 0, 11.5))
    assert monitor.breaches == 2


def test_polygon_geometry():
    assert inside(SQUARE, 0, 0) and not inside(SQUARE, 11, 0)
    assert distance_outside(SQUARE, 13, 0) == pytest.approx(3.0)
    assert distance_outside(SQUARE, 0, 0) == 0.0


@pytest.mark.parametrize(
    "fields, word",
    [
        ({"max_altitude": 0}, "max_altitude"),
        ({"max_distance": math.inf}, "max_distance"),
        ({"max_horizontal_speed": -1}, "max_horizontal_speed"),
        ({"breach_action": "panic"}, "breach_action"),
        ({"fence": [(0.0, 0.0), (1.0, 1.0)]}, "at least 3"),
        ({"fence": [(0.0, 0.0), (1.0, math.nan), (1.0, 1.0)]}, "finite"),
        ({"margin": -1}, "margin"),
    ],
)
def test_bad_envelopes_are_refused_naming_the_field(fields, word):
    with pytest.raises(ValueError, match=word):
        Envelope(**fields)


def test_an_envelope_decodes_strictly():
    decoded = msgspec.json.decode(b'{"max_altitude": 30, "fence": []}', type=Envelope)
    assert decoded.max_altitude == 30
    with pytest.raises(msgspec.ValidationError):
        msgspec.json.decode(b'{"max_alt": 30}', type=Envelope)
