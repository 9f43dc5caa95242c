"""The controller's life cycle on the fake bus, in injected time (bus seconds, not wall time).

The controller (:class:`~dronewrapper_controller.node.Controller`) commands through a
DroneClient on a FakeNode; a :class:`~bus_autopilot.BusAutopilot` holds the bridge's keys with a
simple aircraft. Detections are scheduled at given bus times; every judgement reads bus-time
stamps, so a loaded machine changes nothing. The real process is tested in
test_controller_process.py.

Size: the controller's whole life cycle on one rig, each stage's test beside the stages it
follows.
"""

from __future__ import annotations

import itertools
import math
from concurrent.futures import Future

import pytest
from bus_autopilot import BusAutopilot, drive

from dronewrapper.client import DroneClient
from dronewrapper.msgs import registry
from dronewrapper.msgs.control import (
    CONTROLLER_HOVER,
    CONTROLLER_IDLE,
    CONTROLLER_LANDING,
    CONTROLLER_SEARCH,
    CONTROLLER_TAKEOFF,
    CONTROLLER_TRACKING,
    ControllerStatus,
)
from dronewrapper.msgs.mavros import MASK_VELOCITY, CommandTOL, PositionTarget
from dronewrapper.msgs.std import Header
from dronewrapper.msgs.vision import BoundingBox2D, Detection2D, Detections
from dronewrapper.runtime.config import load_config
from dronewrapper.runtime.fake import FakeBus, FakeNode
from dronewrapper_controller.config import Config
from dronewrapper_controller.node import PORTS, Controller, run

T0 = 1_700_000_000.0  # bus time = Unix time, so frame stamps are real-looking stamps
DETECTIONS_KEY = registry.DETECTIONS.key("drone")


def blob(x: float, y: float, radius: float) -> Detection2D:
    box = BoundingBox2D.at(x, y, 2 * radius, 2 * radius)
    return Detection2D(bbox=box, circle_radius=radius, id="")


class DeferredCalls:
    """The commander's calls, each made at the bus's next wake instead of on a worker thread: a
    request the aircraft answers only once its manoeuvre has ended (the take-off) moves the bus
    on meanwhile, stepping the controller's loop too, so the loop runs during the call as it
    does with the real commander's workers."""

    def __init__(self) -> None:
        self.queue: list[tuple] = []

    def submit(self, call) -> Future:
        future: Future = Future()
        self.queue.append((call, future))
        return future

    def step(self, now: float) -> None:
        while self.queue:
            call, future = self.queue.pop(0)
            try:
                future.set_result(call())
            except Exception as exc:
                future.set_exception(exc)

    def next_wake(self, now: float) -> float:
        return now if self.queue else math.inf

    def shutdown(self, **_: object) -> None:
        self.queue.clear()


class At:
    """Runs ``action`` once, at bus time ``when`` (also while a waiting call moves the bus)."""

    def __init__(self, when: float, action) -> None:
        self.when, self.action = when, action

    def step(self, now: float) -> None:
        if now >= self.when and self.action is not None:
            action, self.action = self.action, None
            action()

    def next_wake(self, now: float) -> float:
        return self.when if self.action is not None else math.inf


class Rig:
    """The controller and an autopilot on one fake bus."""

    def __init__(self, overrides: list[str], *, flying: bool = True, **autopilot) -> None:
        self.bus = FakeBus(start=T0)
        self.config = load_config(Config, None, ["search_delay=1.0", *overrides])
        self.autopilot = (
            None if self.config.dry_run else BusAutopilot(self.bus, flying=flying, **autopilot)
        )
        self.node = FakeNode("controller", self.bus, ports=PORTS)
        commander = (
            None
            if self.config.dry_run
            else DroneClient(self.node, name="controller", inline_calls=True)
        )
        self.calls = DeferredCalls()
        if commander is not None:
            commander.calls._pool = self.calls
        self.ctl = Controller(self.node, self.config, commander)
        self.steppers = [s for s in (self.autopilot, self.ctl, self.calls) if s is not None]
        if self.autopilot is not None:
            self.autopilot.steppers = tuple(self.steppers)

    def now(self) -> float:
        return self.bus.clock()

    def at(self, delay: float, action) -> None:
        """Run ``action`` once ``delay`` s of bus time from now have passed."""
        self.steppers.append(At(self.now() + delay, action))
        if self.autopilot is not None:
            self.autopilot.steppers = tuple(self.steppers)

    def run(self, seconds: float) -> None:
        """Run for ``seconds`` of bus time (or until the controller finished)."""
        drive(self.bus, self.now() + seconds, *self.steppers, stop=lambda: self.ctl.finished)

    def feed(self, *dets: Detection2D, seconds: float, hz: float = 20.0) -> list[float]:
        """Schedule detections (``dets``, maybe none) at ``hz`` from now on; their stamps."""
        start = self.now()
        stamps = [start + i / hz for i in range(1, int(seconds * hz) + 1)]
        for stamp in stamps:
            msg = Detections(
                header=Header(stamp=stamp, frame_id="cam_frontal"),
                detections=list(dets),
                image_width=640,
                image_height=480,
                detector="color",
            )
            self.bus.schedule(stamp, DETECTIONS_KEY, msg)
        return stamps

    def statuses(self, since: float = 0.0) -> list[ControllerStatus]:
        key = registry.CONTROLLER_STATUS.key("drone")
        return [d.msg for d in self.bus.published[key] if d.time >= since]

    def state(self) -> str:
        statuses = self.statuses()
        return statuses[-1].state if statuses else ""

    def velocity(self, since: float = 0.0) -> list[tuple[float, PositionTarget]]:
        assert self.autopilot is not None
        return [
            (t, sp) for t, sp in self.autopilot.setpoints(since) if sp.type_mask == MASK_VELOCITY
        ]

    def last_command(self) -> tuple[float, float, float]:
        _, sp = self.velocity()[-1]
        return (sp.velocity.x, sp.velocity.z, sp.yaw_rate)

    def stop(self, seconds: float = 30.0) -> int:
        self.node.stop()
        self.run(seconds)
        assert self.ctl.finished
        return self.ctl.exit_code


def test_tracks_with_the_frames_stamp_and_right_signs():
    rig = Rig(["takeoff.on_start=false", "on_exit=stop"])
    rig.run(0.5)
    assert rig.node.announced and rig.state() in (CONTROLLER_HOVER, CONTROLLER_SEARCH)
    stamps = rig.feed(blob(200, 140, 8), seconds=2.0)  # up-left of centre, small (far)
    rig.run(2.0)
    tracked = [sp for _, sp in rig.velocity() if sp.header.stamp in stamps]
    assert len({sp.header.stamp for sp in tracked}) >= 35  # one command per frame
    last = tracked[-1]
    assert last.velocity.x > 0  # too far: forward
    assert last.velocity.y == 0.0  # vy stays 0
    assert last.velocity.z > 0  # above centre: climb
    assert last.yaw_rate > 0  # left of centre: turn left (CCW)
    assert last.velocity.x <= rig.config.follow_color.vx.out_limit
    status = rig.statuses()[-1]
    assert status.state == CONTROLLER_TRACKING and status.target_visible
    assert status.source_stamp in stamps and status.mode == "follow_color"
    assert rig.stop() == 0


def test_setpoints_repeat_at_30_hz_and_status_at_its_rate():
    rig = Rig(["takeoff.on_start=false", "on_exit=stop", "status_rate_hz=10"])
    rig.feed(blob(320, 240, 10), seconds=0.5)
    rig.run(3.0)
    times = [t for t, _ in rig.velocity(since=T0 + 1.0)]  # detections stopped: hover, repeated
    gaps = [b - a for a, b in itertools.pairwise(times)]
    assert gaps and max(gaps) <= 1 / 30 + 1e-6  # >= 20 Hz, the setpoint contract
    assert [sp.header.seq for _, sp in rig.autopilot.setpoints()] == list(
        range(len(rig.autopilot.setpoints()))
    )
    stamps = [s.header.stamp for s in rig.statuses()]
    assert all(b - a == pytest.approx(0.1, abs=1e-6) for a, b in itertools.pairwise(stamps))
    assert [s.header.seq for s in rig.statuses()] == list(range(len(stamps)))


def test_stale_detections_hover_never_search_blind_then_search_right():
    rig = Rig(["takeoff.on_start=false", "on_exit=stop", "search_yaw_rate=0.4"])
    rig.run(0.3)
    rig.feed(blob(600, 240, 20), seconds=0.5)  # target on the right ...
    rig.run(0.5)
    assert rig.state() == CONTROLLER_TRACKING
    rig.run(0.6)  # ... then detections stop (perception died): stale after 0.5 s
    assert rig.state() == CONTROLLER_HOVER
    since = rig.now()
    rig.run(1.5)  # longer than search_delay: still hover, never search blind
    assert {s.state for s in rig.statuses(since)} == {CONTROLLER_HOVER}
    assert rig.last_command() == (0.0, 0.0, 0.0)
    rig.feed(seconds=2.0)  # fresh detections without the target: search to the right (cw)
    rig.run(2.0)
    assert rig.state() == CONTROLLER_SEARCH
    assert rig.last_command() == (0.0, 0.0, pytest.approx(-0.4))


def test_stop_sends_zero_for_a_moment_then_nothing_and_never_lands():
    rig = Rig(["takeoff.on_start=false", "on_exit=stop"])
    rig.feed(blob(100, 100, 5), seconds=1.0)
    rig.run(1.0)
    assert rig.velocity() and rig.last_command() != (0.0, 0.0, 0.0)
    stopped_at = rig.now()
    rig.node.stop()
    rig.run(5.0)
    assert rig.ctl.finished and rig.ctl.exit_code == 0
    after = rig.velocity(since=stopped_at)
    assert after and all(
        (sp.velocity.x, sp.velocity.z, sp.yaw_rate) == (0, 0, 0) for _, sp in after
    )
    assert after[-1][0] <= stopped_at + 0.2 + 1e-6  # the stream stopped after 0.2 s
    assert rig.autopilot.called("land") == 0


def test_stop_is_seen_within_one_control_period_while_servoing():
    rig = Rig(["takeoff.on_start=false", "on_exit=land", "rate_hz=20"])
    rig.run(1.0)
    rig.node.stop()
    stopped_at = rig.now()
    rig.run(10.0)
    (called_at,) = [t for t, name in rig.autopilot.calls if name == "flight_land"]
    assert called_at - stopped_at <= 1 / 20 + 1e-6
    assert rig.ctl.exit_code == 0 and not rig.autopilot.armed


def test_takes_off_on_start_watching_only_and_lands_on_exit():
    rig = Rig(["takeoff.height=1.5", "on_exit=land"], flying=False)
    rig.feed(blob(600, 240, 10), seconds=4.0)  # the target is in view during the climb
    rig.run(0.2)
    assert rig.state() == CONTROLLER_TAKEOFF
    assert [name for _, name in rig.autopilot.calls] == ["flight_takeoff"]
    rig.run(3.0)
    assert rig.autopilot.z >= 1.4 and rig.autopilot.mode == "OFFBOARD"
    assert rig.state() == CONTROLLER_TRACKING
    # taking off, the controller only watched: its first velocity command came at the top
    assert rig.autopilot.z_at_first_velocity >= 1.4 - 1e-6
    assert rig.stop() == 0
    assert rig.autopilot.called("flight_land") == 1 and not rig.autopilot.armed
    assert CONTROLLER_LANDING in {s.state for s in rig.statuses()}


def test_a_refused_takeoff_stops_the_stream_and_exits_1():
    refuse = {"flight_takeoff": "no GPS"}
    rig = Rig(["takeoff.height=1.5", "on_exit=land"], flying=False, refuse=refuse)
    rig.run(5.0)
    assert rig.ctl.finished and rig.ctl.exit_code == 1
    assert rig.autopilot.called("flight_takeoff") == 1 and rig.autopilot.z == 0.0
    assert rig.ctl.commander.target is None  # the hold setpoint no longer streamed


def test_a_bridge_that_never_answers_fails_the_takeoff_within_its_timeout():
    rig = Rig(
        ["takeoff.height=1.5", "takeoff.timeout=3", "on_exit=land"],
        flying=False,
        absent=["flight_takeoff"],
    )
    start = rig.now()
    rig.run(10.0)
    assert rig.ctl.finished and rig.ctl.exit_code == 1
    assert rig.now() - start <= 3.5


def test_no_bridge_gives_up_after_ready_timeout_with_exit_1():
    bus = FakeBus(start=T0)
    node = FakeNode("controller", bus, ports=PORTS)
    config = load_config(Config, None, ["ready_timeout=1.5", "takeoff.on_start=false"])
    commander = DroneClient(node, name="c", inline_calls=True)
    ctl = Controller(node, config, commander)
    drive(bus, T0 + 10, ctl, stop=lambda: ctl.finished)
    assert ctl.finished and ctl.exit_code == 1
    assert bus.clock() == pytest.approx(T0 + 1.5, abs=0.11)
    statuses = [d.msg.state for d in bus.published[registry.CONTROLLER_STATUS.key("drone")]]
    assert statuses and set(statuses) == {CONTROLLER_IDLE}
    assert not node.announced


def test_a_stop_while_waiting_for_the_bridge_exits_0_at_once():
    bus = FakeBus(start=T0)
    node = FakeNode("controller", bus, ports=PORTS)
    config = load_config(Config, None, ["ready_timeout=60"])
    commander = DroneClient(node, name="c", inline_calls=True)
    ctl = Controller(node, config, commander)
    drive(bus, T0 + 1.0, ctl)
    node.stop()
    drive(bus, T0 + 2.0, ctl, stop=lambda: ctl.finished)
    assert ctl.finished and ctl.exit_code == 0 and bus.clock() <= T0 + 1.0 + 1 / 20


def test_dry_run_shows_commands_and_sends_none():
    rig = Rig(["mode=follow_color", "dry_run=true"])
    assert rig.node.announced
    stamps = rig.feed(blob(520, 200, 15), seconds=1.0)  # right of centre
    rig.run(1.0)
    status = rig.statuses()[-1]
    assert status.state == CONTROLLER_TRACKING and status.source_stamp in stamps
    assert status.cmd_yaw_rate < 0  # turn right (clockwise, negative)
    assert status.error_yaw != 0
    assert rig.bus.published[registry.SETPOINT_RAW_LOCAL.key("drone")] == []
    assert rig.stop() == 0


def test_a_bad_detections_message_is_counted_and_dropped():
    rig = Rig(["takeoff.on_start=false", "on_exit=stop"])
    rig.feed(blob(320, 240, 10), seconds=0.5)
    bad = Detections(
        header=Header(stamp=float("nan")), detections=[], image_width=640, image_height=480
    )
    rig.bus.schedule(rig.now() + 0.26, DETECTIONS_KEY, bad)
    rig.run(1.0)
    assert rig.node.callback_errors["detections refused"] == 1
    assert rig.stop() == 0


def test_a_stop_during_the_takeoff_lands_at_once():
    rig = Rig(["takeoff.height=3", "on_exit=land"], flying=False)
    seen: dict = {}

    def stop_while_climbing() -> None:
        seen.update(state=rig.state(), z=rig.autopilot.z, at=rig.now())
        rig.node.stop()

    rig.at(1.0, stop_while_climbing)
    rig.run(30.0)
    assert seen["state"] == CONTROLLER_TAKEOFF and 0.5 < seen["z"] < 1.5
    assert rig.ctl.finished and rig.ctl.exit_code == 0
    stopped_at = seen["at"]
    (called_at,) = [t for t, name in rig.autopilot.calls if name == "flight_land"]
    assert called_at - stopped_at <= 1 / 20 + 1e-6
    assert rig.velocity() == []  # never servoed


@pytest.mark.parametrize("dry_run", [True, False])
def test_run_returns_0_soon_after_a_stop(dry_run):
    """The service's loop (``run``) on a fake node, its thread in the bus's virtual time: a
    stop ends it within one control period."""
    node = FakeNode("controller", FakeBus(start=T0), ports=PORTS)
    config = load_config(Config, None, [f"dry_run={str(dry_run).lower()}", "ready_timeout=60"])
    result: list[int] = []
    node.clock.thread(lambda: result.append(run(node, config)), "controller").start()
    node.clock.run_for(1.0)
    assert result == []
    node.stop()
    node.clock.run_until(lambda: result, 1 / config.rate_hz + 1e-6, "the loop's exit")
    assert result == [0]


def test_a_takeoff_refused_while_the_autopilot_gets_ready_is_tried_again():
    rig = Rig(
        ["takeoff.height=1.5", "takeoff.wait_ready=20", "on_exit=land"],
        flying=False,
        refuse={"flight_takeoff": "Arm: Need Position Estimate"},
    )
    rig.run(7.0)  # refused, tried again every 2 s
    assert not rig.ctl.finished and rig.state() == CONTROLLER_TAKEOFF
    assert rig.autopilot.called("flight_takeoff") >= 3 and rig.autopilot.z == 0.0
    rig.autopilot.refuse.clear()  # the autopilot is ready now
    rig.run(6.0)
    assert rig.autopilot.z >= 1.4 and rig.state() == CONTROLLER_HOVER  # up; no target yet
    assert rig.stop() == 0


def test_a_takeoff_still_refused_when_wait_ready_ends_fails():
    rig = Rig(
        ["takeoff.height=1.5", "takeoff.wait_ready=5", "on_exit=land"],
        flying=False,
        refuse={"flight_takeoff": "no GPS"},
    )
    start = rig.now()
    rig.run(20.0)
    assert rig.ctl.finished and rig.ctl.exit_code == 1
    assert rig.now() - start <= 5.5 and rig.autopilot.called("flight_takeoff") >= 2


def test_a_stale_command_is_not_resent_after_a_router_gap():
    """The commander's stream keeps the link-gap rule (runtime.setpoint_stream): a command
    older than the bridge's expiry when the route returns is dropped, never resent."""
    rig = Rig(["takeoff.on_start=false", "on_exit=stop", "detection_timeout=3.0"])
    rig.feed(blob(520, 200, 15), seconds=1.0)
    rig.run(1.0)
    _, stale = rig.velocity()[-1]
    assert stale.yaw_rate != 0  # tracking: the command the loop holds
    rig.bus.link_gap(True)  # the router restarts: the bridge's subscriber unreachable
    rig.run(1.0)
    assert rig.velocity(since=rig.now() - 0.9) == []  # withheld meanwhile
    rig.bus.link_gap(False)
    back = rig.now()
    rig.run(0.5)
    assert rig.velocity(since=back) == [], "the stale command was resent after the gap"
    assert rig.ctl.commander.stream.core.dropped_after_gap == 1
    rig.feed(blob(520, 200, 15), seconds=0.2)  # a new detection: a new command goes out
    rig.run(0.2)
    assert rig.velocity(since=back)
    assert rig.stop() == 0


def test_a_landing_by_another_commander_stops_the_commanding_until_started_again(caplog):
    """The station lands the drone while the follow controller searches: from then on the
    controller sends nothing (no search turn), reports idle, and at exit neither lands nor
    says "landing"."""
    rig = Rig(["takeoff.on_start=false", "on_exit=land", "search_yaw_rate=0.4"])
    rig.feed(seconds=3.0)  # fresh detections without the target: search
    rig.run(2.5)
    assert rig.state() == CONTROLLER_SEARCH and rig.velocity()
    station = FakeNode("station", rig.bus)
    reply = station.call(registry.LAND, CommandTOL.land(), ns="drone")
    assert reply.success
    landed_at = rig.now()
    rig.run(0.2)
    yielded_at = max(t for t, _ in rig.autopilot.setpoints())
    assert yielded_at <= landed_at + 1 / 30 + 1e-6  # no setpoint after the landing was seen
    rig.feed(seconds=2.0)
    rig.run(5.0)  # the drone lands; detections keep coming: still nothing commanded
    assert max(t for t, _ in rig.autopilot.setpoints()) == yielded_at
    assert rig.state() == CONTROLLER_IDLE
    assert not rig.autopilot.armed and rig.autopilot.z == 0.0
    with caplog.at_level("INFO", logger="controller"):
        assert rig.stop() == 0
    assert rig.autopilot.called("land") == 1  # the station's, not the controller's
    assert rig.autopilot.called("flight_land") == 0
    assert "landing" not in [r.getMessage() for r in caplog.records]
