"""The Tello's video on demand, one rule per test: the pure core in given time (tello_core_rig)
with the camera's publishers on the fake bus, so a subscriber that comes and goes is what the
node's CameraWatch sees; what the core sends is exactly what the Tello's port 8889 would get."""

from __future__ import annotations

import itertools
from collections.abc import Callable

import pytest
from tello_core_rig import EPOCH, TelloRig

from dronewrapper.msgs import registry
from dronewrapper.msgs.flight import CancelRequest, TakeoffRequest
from dronewrapper.msgs.mavros import CommandTOL
from dronewrapper.runtime.config import ConfigError, load_config
from dronewrapper.runtime.fake import FakeBus, FakeNode
from dronewrapper_bridge_base.core_driver import cancel_steps
from dronewrapper_bridge_tello import flight
from dronewrapper_bridge_tello import operations as ops
from dronewrapper_bridge_tello.camera_watch import CameraWatch
from dronewrapper_bridge_tello.config import Config
from dronewrapper_bridge_tello.node import PORTS
from dronewrapper_bridge_tello.video_demand import VideoDemand, VideoPolicy

IDLE = 5.0  # s: the rigs' video_idle_s
RETRY = 2.0  # s: video_retry_s


class Viewers:
    """The camera's publishers on a fake bus, a CameraWatch on them, and a viewer's node."""

    def __init__(self) -> None:
        self.bus = FakeBus()
        bridge = FakeNode("bridge_tello", self.bus, ports=PORTS)
        self.raw = bridge.publisher(registry.IMAGE_RAW, camera="cam_frontal")
        self.jpeg = bridge.publisher(registry.IMAGE_COMPRESSED, camera="cam_frontal")
        self.watch = CameraWatch([self.raw, self.jpeg])
        self.viewer = FakeNode("viewer", self.bus)

    def subscribe(self, topic=registry.IMAGE_RAW):
        return self.viewer.subscribe(topic, lambda msg: None, camera="cam_frontal")


def video_rig(mode: str = "on_demand", **config) -> tuple[TelloRig, Viewers]:
    viewers = Viewers()
    config = {"video_idle_s": IDLE, "video_retry_s": RETRY, **config}
    rig = TelloRig(video=mode, **config)
    rig.watched = lambda: viewers.watch.watched
    return rig, viewers


def video_commands(rig: TelloRig, since: float = float("-inf")) -> list[tuple[float, str]]:
    return [(at, t) for at, t in rig.sent if at >= since and t in ("streamon", "streamoff")]


def video_after(rig: TelloRig, act: Callable[[], object], seconds: float) -> list[str]:
    """The video commands sent while ``act()`` then ``seconds`` of running happen."""
    since = rig.now
    act()
    rig.run(seconds)
    return [t for _, t in video_commands(rig, since)]


def test_nobody_watching_the_stream_is_switched_off_once_at_connection():
    rig, _ = video_rig()
    rig.connect()
    rig.run(3.0)
    assert [t for _, t in video_commands(rig)] == ["streamoff"]  # a stream left on is stopped
    assert not rig.video_on and not rig.core.streaming


def test_a_subscriber_appearing_sends_streamon_at_the_next_tick():
    rig, viewers = video_rig()
    rig.connect()
    rig.run(1.0)
    for topic in (registry.IMAGE_RAW, registry.IMAGE_COMPRESSED):  # either camera key
        since = rig.now
        sub = viewers.subscribe(topic)
        rig.run(1.0)
        (at, command), *_ = video_commands(rig, since)
        assert command == "streamon" and at - since <= 0.06 and rig.video_on
        assert rig.core.streaming and rig.video_restarts[-1] == at  # a fresh receiver run
        sub.undeclare()
        rig.run(IDLE + 0.5)


def test_the_last_subscriber_gone_the_stream_stops_after_the_idle_time():
    rig, viewers = video_rig()
    rig.connect()
    first, second = viewers.subscribe(), viewers.subscribe(registry.IMAGE_COMPRESSED)
    rig.run(1.0)
    assert rig.video_on
    first.undeclare()  # one viewer left: the stream runs on
    rig.run(2 * IDLE)
    assert rig.video_on
    left = rig.now
    second.undeclare()
    rig.run(IDLE - 0.1)
    assert video_commands(rig, left) == []
    rig.run(0.3)
    ((at, command),) = video_commands(rig, left)
    assert command == "streamoff" and IDLE <= at - left <= IDLE + 0.1
    assert not rig.video_on and not rig.core.streaming


def test_a_subscriber_back_within_the_idle_time_keeps_the_stream_running():
    rig, viewers = video_rig()
    rig.connect()
    sub = viewers.subscribe()
    rig.run(1.0)
    since = rig.now
    sub.undeclare()
    rig.run(IDLE - 1.0)
    sub = viewers.subscribe()  # back before the idle time is over
    rig.run(3 * IDLE)
    assert video_commands(rig, since) == [] and rig.video_on


@pytest.mark.parametrize("answer", ["error", None])  # refused, or never answered
def test_a_failed_streamon_is_retried_then_given_up_until_the_demand_changes(answer):
    rig, viewers = video_rig(video_attempts=3)
    rig.connect()
    rig.run(1.0)
    rig.script["streamon"] = answer
    since = rig.now
    sub = viewers.subscribe()
    rig.run(30.0)
    tries = [at for at, t in video_commands(rig, since) if t == "streamon"]
    assert len(tries) == 3  # bounded
    assert all(b - a >= RETRY for a, b in itertools.pairwise(tries))
    texts = [m.text for m in rig.published(registry.STATUSTEXT)]
    assert any("streamon" in t and "3 times" in t for t in texts)
    del rig.script["streamon"]  # the Tello would accept now; a new demand tries again
    sub.undeclare()
    rig.run(IDLE + 1.0)
    assert video_after(rig, viewers.subscribe, 1.0) == ["streamon"] and rig.video_on


def test_nothing_is_sent_for_the_video_while_the_tello_is_not_connected():
    rig, viewers = video_rig()
    rig.streaming_state = False  # no state string: not connected (though in SDK mode)
    viewers.subscribe()
    rig.run(5.0)
    assert rig.core.sdk_mode and {t for _, t in rig.sent} == {"command"}  # only reconnections
    rig, viewers = video_rig()
    rig.script["command"] = "error"  # state strings, but no SDK mode
    viewers.subscribe()
    rig.run(3.0)
    assert rig.core.connected and not rig.core.sdk_mode and video_commands(rig) == []
    del rig.script["command"]
    rig.connect()
    rig.run(0.5)
    assert [t for _, t in video_commands(rig)] == ["streamon"]


def test_a_reconnected_tello_gets_its_stream_switched_again():
    rig, viewers = video_rig()
    rig.connect()
    viewers.subscribe()
    rig.run(1.0)
    rig.streaming_state = False  # the Tello power-cycles: its stream is off again
    rig.run(3.0)
    assert not rig.core.connected
    rig.video_on, rig.streaming_state = False, True
    assert video_after(rig, rig.connect, 0.5) == ["streamon"] and rig.video_on


def test_the_video_never_goes_ahead_of_a_flight_command_nor_between_one_and_its_reply():
    rig, viewers = video_rig()
    rig.connect()
    rig.run(1.0)
    rig.delays["takeoff"] = 3.0
    takeoff = rig.start(ops.takeoff, CommandTOL.takeoff())
    viewers.subscribe()  # while the take-off waits for its ok
    rig.run(1.0)
    assert "streamon" not in rig.commands()
    land = rig.start(ops.land, CommandTOL.land())  # asked later than the viewer came
    rig.run(10.0, until=lambda: land.done)
    assert takeoff.result().success and land.result().success
    rig.run(0.5)
    assert rig.commands()[-3:] == ["takeoff", "land", "streamon"]  # the flight first
    viewers.bus.link_gap(True)  # the viewer gone: streamoff after the idle time
    rig.run(IDLE + 0.5)
    viewers.bus.link_gap(False)
    rig.delays["streamon"] = 0.5
    rig.run(0.06)  # streamon sent, its reply 0.5 s away
    takeoff = rig.start(ops.takeoff, CommandTOL.takeoff())
    rig.run(5.0, until=lambda: takeoff.done)
    sent = [(at, t) for at, t in rig.sent if t in ("streamon", "takeoff")]
    assert [t for _, t in sent[-2:]] == ["streamon", "takeoff"]
    assert sent[-1][0] - sent[-2][0] >= 0.5  # the take-off only once streamon was answered


def test_a_slot_freed_between_ticks_goes_to_the_waiting_flight_command_not_the_video():
    rig, viewers = video_rig()
    rig.connect()
    rig.run(1.0)
    rig.delays["up 200"] = 10.0  # the climb to 3 m holds the slot
    takeoff = rig.start(flight.takeoff_to, TakeoffRequest(height=3.0))
    rig.run(10.0, until=lambda: "up 200" in rig.commands())
    land = rig.start(ops.land, CommandTOL.land())  # waits for the slot
    viewers.subscribe()  # the video waits for it too
    rig.run(0.2)
    since = rig.now
    rig.script["stop"] = None  # the cancel's stop is answered by hand, between two ticks
    assert rig.start(cancel_steps, CancelRequest()).result().success
    assert takeoff.done and rig.commands(since) == ["stop"]
    rig.reply_now("ok")  # the stop answered: the slot is free, the land not resumed yet
    assert not rig.core.command_busy and not land.done
    rig.core.tick(rig.now, rig.now + EPOCH, camera_watched=rig.watched())  # the next tick
    rig.collect()
    assert rig.commands(since) == ["stop", "land"]  # the flight command first
    rig.run(5.0, until=lambda: land.done)
    rig.run(0.5)
    assert land.result().success and rig.commands(since) == ["stop", "land", "streamon"]


def test_mode_on_streams_at_connection_and_mode_off_never_touches_the_stream():
    rig, _ = video_rig("on")
    rig.connect()
    rig.run(0.5)
    assert [t for _, t in video_commands(rig)] == ["streamon"]
    rig, viewers = video_rig("off")
    viewers.subscribe()
    rig.connect()
    rig.run(3.0)
    assert video_commands(rig) == []


def test_the_demand_alone_in_given_time():
    demand = VideoDemand(VideoPolicy(mode="on_demand", idle_s=2.0, retry_s=1.0, attempts=2))
    step = {"connected": True, "slot_free": True}
    assert demand.next_command(0.0, watched=True, **step) == "streamon"
    assert demand.next_command(0.1, watched=True, **step) is None  # one in flight at a time
    demand.on_result("streamon", True, 0.2)
    assert demand.next_command(0.3, watched=False, **step) is None  # idle time running
    assert demand.next_command(2.2, watched=False, slot_free=False, connected=True) is None
    assert demand.next_command(2.35, watched=False, **step) == "streamoff"
    demand.on_result("streamoff", False, 2.4)
    assert demand.next_command(3.0, watched=False, **step) is None  # retry_s not over
    assert demand.next_command(3.4, watched=False, **step) == "streamoff"
    demand.on_result("streamoff", False, 3.5)
    assert demand.gave_up and demand.next_command(9.0, watched=False, **step) is None
    assert demand.next_command(9.1, watched=False, connected=False, slot_free=True) is None
    assert demand.streaming is None and not demand.gave_up  # unknown again after the link


def test_video_keys_are_strict_and_the_yaml_booleans_still_read():
    assert load_config(Config, None, ["video=true"]).video == "on"
    assert load_config(Config, None, ["video=off"]).video == "off"  # YAML's off
    assert load_config(Config, None, ["video=on_demand"]).video == "on_demand"
    with pytest.raises(ConfigError, match=r"\$\.video"):
        load_config(Config, None, ["video=sometimes"])
    for key, value in (("video_idle_s", "-1"), ("video_retry_s", "0"), ("video_attempts", "0")):
        with pytest.raises(ConfigError, match=key):
            load_config(Config, None, [f"{key}={value}"])
