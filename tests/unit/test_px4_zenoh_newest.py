"""PX4's high-rate topics coalesced before decoding (:mod:`dronewrapper_bridge_px4_zenoh.newest`
and the core's tick): the newest raw sample per topic is kept, the tick decodes only it, in
attitude-then-position order, the version check still first, global position only when due."""

from __future__ import annotations

import pytest
from px4_zenoh_rig import Px4Rig, recorded_key

from dronewrapper.msgs import registry
from dronewrapper_bridge_px4_zenoh import topics as t
from dronewrapper_bridge_px4_zenoh.newest import NewestSamples, RawSample
from dronewrapper_ros2_codec import cdr


def test_the_newest_sample_of_each_topic_is_kept_until_taken():
    inbox = NewestSamples()
    for i in range(3):
        inbox.put("a", f"k{i}", bytes([i]))
    inbox.put("b", "kb", b"b")
    assert inbox.take() == {"a": RawSample("k2", b"\x02"), "b": RawSample("kb", b"b")}
    assert (inbox.received, inbox.replaced) == (4, 2)
    assert inbox.take() == {} and len(inbox) == 0


def put(rig: Px4Rig, topic: t.Px4Topic, *, key: str = "", **changes) -> None:
    """PX4 publishes ``topic`` (its recorded value with ``changes``) into the core's inbox, as
    the node's receive callback does."""
    value = rig.values[topic.name]
    value.update(changes)
    rig.core.inbox.put(topic.name, key or recorded_key(topic), cdr.encode(topic.type_name, value))


@pytest.fixture
def rig() -> Px4Rig:
    rig = Px4Rig()
    rig.boot()
    rig.clear()
    return rig


def test_many_positions_between_ticks_are_one_decode_of_the_newest(rig):
    decoded = rig.core.samples_received
    for i in range(10):  # PX4's ~110 Hz between two 30 Hz ticks, and attitudes in between
        put(rig, t.ATTITUDE)
        put(rig, t.LOCAL_POSITION, x=float(i), y=0.0, z=-2.0)
    assert rig.core.samples_received == decoded  # nothing decoded before the tick
    rig.now += 1 / 30
    rig.tick()
    assert rig.core.samples_received == decoded + 2  # one attitude, one position
    (pose,) = rig.published(registry.LOCAL_POSE)
    assert (pose.pose.position.x, pose.pose.position.y, pose.pose.position.z) == (0.0, 9.0, 2.0)


def test_the_first_pose_needs_attitude_and_position_of_one_tick():
    rig = Px4Rig()
    rig.tokens()
    put(rig, t.LOCAL_POSITION)  # put before the attitude: decoded after it all the same
    put(rig, t.ATTITUDE)
    rig.tick()
    assert len(rig.published(registry.LOCAL_POSE)) == 1 and rig.core.connected


def test_a_coalesced_sample_in_another_version_is_not_decoded(rig):
    decoded = rig.core.samples_received
    other = recorded_key(t.LOCAL_POSITION).rsplit("/", 1)[0] + "/RIHS01_" + "ab" * 32
    put(rig, t.LOCAL_POSITION, key=other)
    rig.now += 1 / 30
    rig.tick()
    assert rig.core.samples_received == decoded and "version" in rig.errors
    assert rig.published(registry.LOCAL_POSE) == []


def test_global_position_is_decoded_only_when_due(rig):
    decoded = rig.core.samples_received
    for _ in range(30):  # 1 s of ticks at 30 Hz, a global position before each
        put(rig, t.GLOBAL_POSITION)
        rig.now += 1 / 30
        rig.tick()
    published = len(rig.published(registry.GLOBAL_POSITION))
    assert 9 <= published <= 11  # global_position_max_hz: 10
    assert rig.core.samples_received - decoded == published
    assert rig.core.connected  # skipped samples still show PX4 is there


def test_battery_is_decoded_only_for_its_periodic_publication(rig):
    decoded = rig.core.samples_received
    for i in range(60):  # 2 s of ticks at 30 Hz, PX4's ~100 Hz battery_status before each
        put(rig, t.BATTERY, voltage_v=15.0 + i / 100)
        rig.now += 1 / 30
        rig.tick()
    published = rig.published(registry.BATTERY)
    assert 3 <= len(published) <= 5  # battery_rate_hz: 2
    assert rig.core.samples_received - decoded <= len(published) + 1
    assert published[-1].voltage > 15.4  # a recent sample, not the first one kept
