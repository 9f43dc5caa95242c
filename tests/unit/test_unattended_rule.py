"""The unattended-action rule (bridge_base/unattended.py): a go-to or mission whose commander's
process stopped beating ends as for a lost commander once the action has ended (the request is
the first beat); a return is left to finish; the action is taken once."""

from __future__ import annotations

import pytest

from dronewrapper_bridge_base.unattended import Unattended, UnattendedConfig

KEY = "drone/alive/app"


def test_a_lost_commander_is_acted_on_once_the_action_has_ended():
    rule = Unattended(UnattendedConfig(lost_timeout=5.0, action="return"))
    rule.start("mission", KEY, 0.0)
    assert rule.watching == KEY
    rule.on_alive({KEY}, 1.0)
    rule.on_alive(set(), 2.0)
    assert rule.tick(6.0, holding=False) == ""  # not gone long enough
    assert rule.tick(6.5, holding=False) == ""  # gone, but the mission still flies
    assert rule.tick(7.0, holding=True) == "return"
    assert "gone for 6.0 s" in rule.reason(7.0)
    assert rule.tick(8.0, holding=True) == ""  # once
    assert rule.watching == ""


def test_a_live_commander_and_a_return_are_not_acted_on():
    rule = Unattended(UnattendedConfig(action="land"))
    rule.start("goto", KEY, 0.0)
    for t in range(1, 20):
        rule.on_alive({KEY}, float(t))
    rule.ended(19.0)
    assert rule.tick(20.0, holding=True) == ""
    rule.start("goto", "drone/alive/other", 0.0)  # the request, then never a beat: lost
    assert rule.tick(6.0, holding=True) == "land"
    rule.start("return", KEY, 0.0)
    rule.on_alive({KEY}, 1.0)
    assert rule.tick(60.0, holding=True) == ""
    rule.start("goto", KEY, 0.0)
    rule.on_alive({KEY}, 1.0)
    rule.ended(2.0)
    assert rule.tick(7.0, holding=False) == "land"  # a reached go-to has ended


def test_nothing_is_watched_without_a_key_or_after_clear():
    rule = Unattended()
    rule.start("mission", "", 0.0)
    assert rule.watching == "" and rule.tick(100.0, holding=True) == ""
    rule.start("mission", KEY, 0.0)
    rule.on_alive({KEY}, 1.0)
    rule.clear()
    assert rule.tick(100.0, holding=True) == ""


@pytest.mark.parametrize(
    "config", [{"action": "hold"}, {"lost_timeout": 0.0}, {"lost_timeout": float("nan")}]
)
def test_a_bad_config_is_refused_naming_the_key(config):
    with pytest.raises(ValueError, match="unattended_"):
        UnattendedConfig(**config)
