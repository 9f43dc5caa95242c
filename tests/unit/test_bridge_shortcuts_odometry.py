"""bridge_base's command-line shortcuts and odometry builder, on their own (pure)."""

from __future__ import annotations

import argparse
import math

import pytest

from dronewrapper.msgs.geometry import Vector3
from dronewrapper.rotations import quat_from_rpy
from dronewrapper_bridge_base.odometry import FRAME_BASE_LINK, Headers, odometry
from dronewrapper_bridge_tello.flags import SHORTCUTS


def test_each_shortcut_given_is_one_override_and_an_absent_one_none():
    parser = argparse.ArgumentParser()
    SHORTCUTS.add_flags(parser)
    overrides = ["video=off"]
    SHORTCUTS.as_overrides(parser.parse_args(["--tello", "127.0.0.2"]), overrides)
    assert overrides == ["video=off", "tello_address=127.0.0.2"]
    assert "--set local_address=ADDRESS" in " ".join(parser.format_help().split())


def test_odometry_numbers_each_kind_and_turns_the_velocity_into_the_body_frame():
    headers = Headers()
    facing_north = quat_from_rpy(0.0, 0.0, math.pi / 2)
    rates = Vector3(z=0.5)
    motion = ((1.0, 2.0, 3.0), facing_north, (0.0, 2.0, 0.0))  # m, attitude, m/s north
    odometry(headers, "map", 10.0, motion, rates, rates)
    pose, local, body = odometry(headers, "map", 11.0, motion, rates, rates)
    assert [m.header.seq for m in (pose, local, body)] == [2, 2, 2]
    assert (pose.header.frame_id, body.header.frame_id) == ("map", FRAME_BASE_LINK)
    assert (pose.pose.position.x, pose.pose.orientation.z) == (1.0, pytest.approx(math.sqrt(0.5)))
    assert local.twist.linear == Vector3(y=2.0) and local.twist.angular == rates
    v = body.twist.linear
    assert (v.x, v.y, v.z) == (pytest.approx(2.0), pytest.approx(0.0, abs=1e-12), 0.0)
