"""What an envelope may be, and a bridge's envelope/set request applied to it: a ceiling of at
least 1 m, a fence containing home or the aircraft, a reset to the configured envelope, and
who set the one in force (dronewrapper.envelope; services/bridge_base: breach.py,
envelope_set.py)."""

from __future__ import annotations

from dataclasses import dataclass, field

import pytest

from dronewrapper import envelope as env
from dronewrapper.envelope import Envelope, EnvelopeError
from dronewrapper.msgs.mission import EnvelopeSet
from dronewrapper.runtime.errors import ServiceError
from dronewrapper_bridge_base import envelope_set
from dronewrapper_bridge_base.breach import BreachMonitor, check_replacement

AWAY = [(20.0, 20.0), (30.0, 20.0), (30.0, 30.0), (20.0, 30.0)]
AROUND_HOME = [(-5.0, -5.0), (5.0, -5.0), (5.0, 5.0), (-5.0, 5.0)]


@dataclass
class State:
    envelope: Envelope = field(default_factory=Envelope)
    monitor: BreachMonitor = field(default_factory=BreachMonitor)
    set_by: str = ""


def test_a_ceiling_below_one_metre_is_refused_naming_the_field():
    with pytest.raises(ValueError, match="max_altitude must be at least 1 m"):
        Envelope(max_altitude=0.1)
    assert Envelope(max_altitude=env.MIN_ALTITUDE_M).max_altitude == 1.0


def test_a_fence_must_contain_home_or_the_aircraft():
    check_replacement(Envelope(fence=AROUND_HOME), None)
    check_replacement(Envelope(fence=AWAY), (25.0, 25.0))  # the aircraft is in it
    check_replacement(Envelope(), None)  # no fence
    with pytest.raises(EnvelopeError, match="neither home nor the aircraft at") as error:
        check_replacement(Envelope(fence=AWAY), (0.0, 0.0))
    assert error.value.limit == "fence"


def test_a_replacement_is_refused_or_applied_and_names_who_set_it():
    state, configured = State(), Envelope()
    with pytest.raises(ServiceError, match="fence contains neither home") as error:
        envelope_set.apply(
            state,
            EnvelopeSet(envelope=Envelope(fence=AWAY)),
            configured=configured,
            caller="ada",
            aircraft=(0.0, 0.0),
        )
    assert error.value.code == "refused" and state.envelope == configured
    wanted = Envelope(max_altitude=15.0, fence=AROUND_HOME)
    request = EnvelopeSet(envelope=wanted)
    assert envelope_set.apply(state, request, configured=configured, caller="ada", aircraft=None)
    assert (state.envelope, state.set_by) == (wanted, "ada")
    reply = envelope_set.result(state)
    assert reply.set_by == "ada" and "'ada'" in reply.message
    read = EnvelopeSet()
    assert not envelope_set.apply(state, read, configured=configured, caller="bob", aircraft=None)
    reset = EnvelopeSet(reset=True)
    assert envelope_set.apply(state, reset, configured=configured, caller="bob", aircraft=None)
    assert (state.envelope, state.set_by) == (configured, "")
    assert envelope_set.result(state).set_by == ""


def test_the_limit_crossed_is_named():
    fenced = Envelope(max_altitude=10.0, fence=AROUND_HOME, margin=0.0)
    monitor = BreachMonitor()
    assert monitor.update(fenced, (8.0, 0.0, 3.0)) and monitor.limit == "fence"
    assert env.violated(fenced, 0.0, 0.0, 12.0)[0] == "max_altitude"
    with pytest.raises(EnvelopeError) as error:
        env.check_velocity(fenced, 0.0, 0.0, 9.0)
    assert error.value.limit == "max_vertical_speed"
