"""The runtime's fake bus: delivery in injected time, Node's surface, registry types."""

from __future__ import annotations

import itertools

import pytest

from dronewrapper.msgs import (
    CommandBool,
    CommandBoolResult,
    Header,
    Point,
    Pose,
    PoseStamped,
    codec,
    registry,
)
from dronewrapper.record.capture import ImageThrottle
from dronewrapper.record.replayer import ReplayClock
from dronewrapper.runtime import ServiceError, ServiceUnavailable
from dronewrapper.runtime.caller import commander_attachment, current_commander
from dronewrapper.runtime.fake import FakeBus, FakeNode


def _pose(x: float) -> PoseStamped:
    return PoseStamped(header=Header(stamp=x), pose=Pose(position=Point(x=x)))


def test_messages_arrive_in_time_order_with_the_clock_at_their_time():
    bus = FakeBus(start=100.0)
    node = FakeNode("test", bus)
    seen = []
    node.subscribe(registry.LOCAL_POSE, lambda m: seen.append((bus.clock(), m.pose.position.x)))
    bus.schedule(102.0, registry.LOCAL_POSE.key(), _pose(2))
    bus.schedule(101.0, registry.LOCAL_POSE.key(), codec.encode(_pose(1)))
    assert bus.next_time() == 101.0
    assert bus.run_until(101.5) == 1 and seen == [(101.0, 1.0)] and bus.clock() == 101.5
    assert bus.step() and seen[-1] == (102.0, 2.0)
    assert not bus.step()


def test_latest_ages_with_the_bus_clock():
    bus = FakeBus(start=0.0)
    node = FakeNode("test", bus)
    latest = node.latest(registry.LOCAL_POSE)
    bus.schedule(1.0, registry.LOCAL_POSE.key(), _pose(1))
    bus.run_until(1.25)
    assert latest.age() == pytest.approx(0.25)
    assert latest.fresh(0.2) is None and latest.fresh(0.3).pose.position.x == 1


def test_publishers_reach_wildcard_subscribers_and_are_kept():
    bus = FakeBus(start=5.0)
    a, b = FakeNode("a", bus), FakeNode("b", bus, ns="drone2")
    got = []
    a.subscribe(registry.LOCAL_POSE, got.append, key="*/mavros/local_position/pose")
    pub = b.publisher(registry.LOCAL_POSE)
    pub.put(_pose(3))
    assert [m.pose.position.x for m in got] == [3.0]
    (sent,) = bus.published["drone2/mavros/local_position/pose"]
    assert sent.time == 5.0 and sent.msg.pose.position.x == 3
    with pytest.raises(TypeError):
        pub.put(Header())


def test_undecodable_payloads_are_counted_not_delivered():
    bus = FakeBus()
    node = FakeNode("test", bus)
    got = []
    node.subscribe(registry.LOCAL_POSE, got.append)
    bus.schedule(1.0, registry.LOCAL_POSE.key(), b"\xc1")
    bus.step()
    assert got == [] and node.decode_errors[registry.LOCAL_POSE.key()] == 1


def test_services_answer_and_refuse_like_the_real_node():
    bus = FakeBus()
    server, client = FakeNode("bridge", bus), FakeNode("sdk", bus)

    def arm(req: CommandBool) -> CommandBoolResult:
        if not req.value:
            raise ValueError("disarm refused")
        return CommandBoolResult(success=True)

    server.serve(registry.ARMING, arm)
    assert client.call(registry.ARMING, CommandBool(value=True)).success
    with pytest.raises(ServiceError, match="disarm refused"):
        client.call(registry.ARMING, CommandBool(value=False))
    with pytest.raises(ServiceUnavailable):
        client.call(registry.ARMING, CommandBool(value=True), ns="drone9")


def test_sleep_moves_time_and_stop_ends_it():
    bus = FakeBus(start=0.0)
    node = FakeNode("test", bus)
    assert node.sleep(0.5) and bus.clock() == 0.5
    node.stop()
    assert not node.sleep(0.5) and node.stopping


def test_replay_clock_maps_recorded_to_wall_time():
    clock = ReplayClock(recorded0=1000.0, wall0=5.0, rate=2.0)
    assert clock.wall_time(1004.0) == 7.0 and clock.recorded_time(7.0) == 1004.0
    with pytest.raises(ValueError):
        ReplayClock(0.0, 0.0, rate=0.0)


def test_image_throttle_keeps_the_mean_rate_without_bursts():
    throttle = ImageThrottle(6.0)
    key = registry.IMAGE_RAW.key(camera="cam_frontal")
    kept = [i for i in range(90) if throttle.keep(key, 10.0 + i / 30)]  # 3 s at 30 Hz
    assert len(kept) == 18
    assert all(b - a == 5 for a, b in itertools.pairwise(kept))
    assert throttle.keep(registry.LOCAL_POSE.key(), 10.0)  # not a camera: always kept


def test_a_publisher_is_watched_while_a_subscription_matches():
    bus = FakeBus()
    camera, viewer = FakeNode("camera", bus), FakeNode("viewer", bus)
    pub = camera.publisher(registry.IMAGE_RAW, camera="cam_frontal")
    assert not pub.watched()
    sub = viewer.subscribe(registry.IMAGE_RAW, lambda m: None, key="*/*/image_raw")
    assert pub.watched()
    sub.undeclare()
    assert not pub.watched()


def test_a_call_carries_its_commander_to_the_handler():
    bus = FakeBus()
    server, client = FakeNode("bridge", bus), FakeNode("sdk", bus)
    asked = []

    def arm(req: CommandBool) -> CommandBoolResult:
        asked.append(current_commander())
        return CommandBoolResult(success=True)

    server.serve(registry.ARMING, arm)
    client.call(registry.ARMING, CommandBool(value=True), attachment=commander_attachment("ada"))
    client.call(registry.ARMING, CommandBool(value=True))
    assert asked == ["ada", ""]
