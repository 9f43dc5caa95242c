"""MissionProgress: what ``reached`` and ``finished`` say before, during and after a mission."""

from __future__ import annotations

from dronewrapper.missions import MissionProgress


def test_before_any_item_is_reached_reached_is_none_and_not_finished():
    progress = MissionProgress(current=0, total=3)
    assert progress.reached is None and not progress.finished


def test_finished_once_the_last_item_is_reached():
    assert not MissionProgress(current=2, total=3, reached=1).finished
    assert MissionProgress(current=2, total=3, reached=2).finished
    assert not MissionProgress(current=0, total=0).finished  # no mission: nothing to finish
