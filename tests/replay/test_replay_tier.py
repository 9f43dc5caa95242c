"""The replay tier: recorded simulator flights through perception and the controller.

Inputs are the recordings in ``data/`` (made by ``record_sim.py``); outputs are compared with the
stored references (``refresh.py`` renews them and reports the differences). ``holdout_teleop``
was flown on a path nothing was tuned on; it is also judged against what the live flight did.
"""

from __future__ import annotations

import json

import pytest
from replay_harness import (
    CAMERA,
    HOLDOUT,
    RECORDINGS,
    compare,
    detection_rows,
    outputs,
    recording,
    reference_path,
    replay_perception,
)

from dronewrapper.msgs import registry
from dronewrapper.record.reader import read_bus, summarize

NAMES = list(RECORDINGS)


@pytest.fixture(scope="module", params=NAMES)
def replayed(request):
    return request.param, outputs(request.param)


def test_recordings_are_small_whole_and_from_the_simulator():
    for name in NAMES:
        path = recording(name)
        info = summarize(path)
        assert path.stat().st_size < 800_000, name
        assert not info.truncated and 2.0 < info.duration_s < 10.0
        topics = {c.topic: c for c in info.channels}
        frames = topics["/" + registry.IMAGE_RAW.key(camera=CAMERA)]
        assert frames.schema == "foxglove.CompressedImage" and frames.count >= 10
        assert topics[registry.SIM_GROUND_TRUTH.key()].count > 0  # the simulator's truth


def test_outputs_match_the_references(replayed):
    name, got = replayed
    diff = compare(got, json.loads(reference_path(name).read_text()))
    assert not diff.problems, diff.report(name)


def test_replay_is_deterministic():
    first = [detection_rows(d) for d in replay_perception(HOLDOUT)]
    again = [detection_rows(d) for d in replay_perception(HOLDOUT)]
    assert first == again


@pytest.mark.parametrize("name", NAMES)
def test_replayed_perception_reproduces_the_live_detections(name):
    """Same frames (by capture stamp), same target box within JPEG's few pixels."""
    live = {
        m.decode().header.stamp: m.decode()
        for m in read_bus(recording(name), [registry.DETECTIONS.key()])
    }
    replayed = replay_perception(name)
    matched = 0
    for det in replayed:
        ref = live.get(det.header.stamp)
        if ref is None or ref.target() is None:
            continue
        matched += 1
        got, want = det.target(), ref.target()
        assert got is not None, f"frame {det.header.stamp:.3f}: target lost in replay"
        dx = got.bbox.center.position.x - want.bbox.center.position.x
        dy = got.bbox.center.position.y - want.bbox.center.position.y
        assert abs(dx) < 4.0 and abs(dy) < 4.0, (det.header.stamp, dx, dy)
        assert got.bbox.size_x == pytest.approx(want.bbox.size_x, rel=0.15, abs=3)
    assert matched >= 0.8 * len(replayed) > 0


def test_holdout_flight_is_followed(replayed):
    """On the never-tuned path, the target stays found and the yaw command turns toward it."""
    name, got = replayed
    if name != HOLDOUT:
        return
    frames = got["perception"]
    assert sum(1 for f in frames if f["target_id"]) >= 0.9 * len(frames)
    width = next(
        m.decode().image_width for m in read_bus(recording(name), [registry.DETECTIONS.key()])
    )
    offsets = {
        f["stamp"]: next(d["cx"] for d in f["detections"] if d["id"] == f["target_id"]) - width / 2
        for f in frames
        if f["target_id"]
    }
    live_cmds = [m.decode() for m in read_bus(recording(name), [registry.CONTROLLER_STATUS.key()])]
    assert live_cmds, "the recording has the live controller's status"
    checked = 0
    for cmd in got["controller"]:
        offset = offsets.get(cmd["source_stamp"])
        if cmd["state"] != "tracking" or offset is None or abs(offset) < 2.0:
            continue
        checked += 1
        # image x to the right, yaw counter-clockwise positive: target right -> turn right (< 0)
        assert cmd["yaw_rate"] * offset < 0, (cmd, offset)
    assert checked >= 5


def test_the_followed_person_keeps_its_identity_through_the_crossing():
    """people_crossing_front: a passer-by walks between the drone and the target (ground truth:
    the target stands straight ahead, so at the image's centre column)."""
    name = "people_crossing_front"
    frames = [detection_rows(d) for d in replay_perception(name)]
    truth = [m.decode() for m in read_bus(recording(name), ["sim/objects/person1/pose"])]
    assert truth[0].pose.position.y < -1.0 < 1.0 < truth[-1].pose.position.y  # it crossed
    assert max(len(f["detections"]) for f in frames) >= 2  # the passer-by was seen
    followed = {f["target_id"] for f in frames if f["target_id"]}
    assert len(followed) == 1, followed
    for f in frames:
        for det in f["detections"]:
            if det["id"] == f["target_id"]:
                assert abs(det["cx"] - 320) < 20, f
    assert sum(1 for f in frames if f["target_id"]) >= 0.8 * len(frames)


def test_the_comparison_catches_moved_outputs():
    ref = json.loads(reference_path(HOLDOUT).read_text())
    moved = json.loads(json.dumps(ref))
    moved["perception"][3]["detections"][0]["cx"] += 1.5
    moved["controller"][5]["yaw_rate"] += 0.01
    moved["controller"].pop()
    diff = compare(moved, ref)
    report = diff.report(HOLDOUT)
    assert len(diff.problems) == 3, report
    assert "perception[3]" in report and "controller[5]" in report and "commands" in report
    assert diff.max_bbox_px == pytest.approx(1.5)
