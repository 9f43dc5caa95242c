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


def test_finished_once_the_last_item_that_flies_is_reached_not_a_camera_item_after_it():
    # a QGroundControl survey ends with DO_SET_CAM_TRIGG_DIST, which no autopilot reports
    # reached: items 0-11, the last that flies is 11, item 12 turns the camera off
    assert not MissionProgress(current=11, total=13, reached=10, last_flown=11).finished
    assert MissionProgress(current=12, total=13, reached=11, last_flown=11).finished
