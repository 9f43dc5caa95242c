"""Go-to, return and missions as bridge operations, at their edges: bridge_mavlink's core
against the simulator's PX4-like autopilot (tests/sim_pair.py: real MAVLink bytes, virtual
time), judged from the simulator's ground truth.

Each test holds one rule of docs/design.md "Long actions": a breach return stays under the
ceiling and takes the asked action; a go-to never guesses home; local missions fly in metres;
a take-off's timeout stops the climb; mission calls with nothing to do are refused without a
mode change; an unattended action whose commander died ends on the ground. Figures print
with ``-s``.
"""

from __future__ import annotations

import math

from sim_pair import EPOCH, SimPair

from dronewrapper.envelope import Envelope
from dronewrapper.msgs import registry
from dronewrapper.msgs.flight import (
    CANCELLED,
    NO_HOME,
    REFUSED,
    TOO_LATE,
    CancelRequest,
    GotoRequest,
    LandRequest,
    MissionRequest,
    ReturnRequest,
    TakeoffRequest,
)
from dronewrapper.msgs.geometry import Vector3
from dronewrapper.msgs.mavros import FRAME_BODY_NED, MASK_VELOCITY, PositionTarget, SetMode
from dronewrapper.msgs.mission import EnvelopeSet, WaypointPush
from dronewrapper.plan import waypoints_of
from dronewrapper_bridge_base.core_driver import cancel_steps
from dronewrapper_bridge_mavlink import actions, flight, missions
from dronewrapper_bridge_mavlink import operations as ops

FAST_RTL = {"RTL_DESCEND_ALT": 3.0, "RTL_LAND_DELAY": 0.0}
APP = "drone/alive/app"


def east_velocity(speed: float) -> PositionTarget:
    """``speed`` m/s forward (the vehicle faces east at the start)."""
    return PositionTarget(
        coordinate_frame=FRAME_BODY_NED, type_mask=MASK_VELOCITY, velocity=Vector3(x=speed)
    )


def square_fence(half: float) -> list[tuple[float, float]]:
    return [(-half, -half), (half, -half), (half, half), (-half, half)]


def fly_out_of_the_fence(half: float, speed: float) -> tuple[SimPair, float]:
    """Take off to 4 m, set a 15 m ceiling and a fence of ±``half`` m (breach: return), then fly
    east at ``speed`` m/s in OFFBOARD; the pair, and when the fence was crossed."""
    pair = SimPair(params=dict(FAST_RTL))  # RTL_RETURN_ALT left at PX4's 30 m
    pair.take_off(4.0)
    envelope = Envelope(max_altitude=15.0, fence=square_fence(half), breach_action="return")
    assert pair.call(missions.set_envelope, EnvelopeSet(envelope=envelope)).success
    pair.run(3.0)  # the fence, return altitude and fence action reach the autopilot
    pair.setpoint = east_velocity(speed)
    pair.call(ops.set_mode, SetMode(custom_mode="OFFBOARD"))
    assert pair.run(20.0, until=lambda: pair.position[0] > half), "never crossed the fence"
    return pair, pair.t


def test_a_breach_return_never_climbs_above_the_ceiling_and_lands_home():
    pair, crossed = fly_out_of_the_fence(10.0, 10.0)
    assert pair.run(10.0, until=lambda: pair.autopilot.mode.name == "RTL"), "no return"
    pair.setpoint = None  # the app has stopped steering
    pair.run(1.0)
    states = pair.published(registry.STATE, crossed)
    assert any(s.failsafe == "breach:return" for s in states), {s.failsafe for s in states}
    assert pair.run(120.0, until=lambda: not pair.autopilot.armed), "not back and landed"
    highest = max(p[2] for t, p, _ in pair.truth if t >= crossed)
    landed = math.hypot(pair.position[0], pair.position[1])
    print(f"\nbreach return: highest {highest:.2f} m (ceiling 15), landed {landed:.2f} m off")
    assert highest <= 15.0
    assert landed < 2.0


def test_the_autopilots_own_fence_takes_the_requested_return():
    """At 3 m/s the autopilot's polygon fence (no margin) fires before the bridge's breach: its
    action must be the envelope's return, not a hold at the edge."""
    pair, crossed = fly_out_of_the_fence(8.0, 3.0)
    assert pair.run(10.0, until=lambda: pair.autopilot.mode.name == "RTL"), (
        f"no return: {pair.autopilot.mode.name}"
    )
    pair.setpoint = None
    print(f"\nautopilot fence: return {pair.t - crossed:.2f} s after the fence was crossed")
    assert pair.run(120.0, until=lambda: not pair.autopilot.armed), "not back and landed"
    assert max(p[2] for t, p, _ in pair.truth if t >= crossed) <= 15.0


def test_a_return_request_keeps_under_the_ceiling_and_answers_on_the_ground():
    pair = SimPair(params=dict(FAST_RTL), envelope=Envelope(max_altitude=12.0))
    pair.take_off(4.0)
    reply = pair.call(actions.goto_point, GotoRequest(x=15.0, y=0.0, z=4.0), limit=40.0)
    assert reply.success, reply.message
    since = pair.t
    reply = pair.call(actions.return_home, ReturnRequest(timeout=120.0), limit=130.0)
    assert reply.success, reply.message
    assert not pair.autopilot.armed and math.hypot(*pair.position[:2]) < 1.0
    assert max(p[2] for t, p, _ in pair.truth if t >= since) <= 12.0


def test_goto_waits_for_home_and_flies_to_the_point_from_home_not_from_the_origin():
    """Home (where the autopilot armed, 6 m east of the local origin) is not known yet when
    the go-to starts: the bridge waits for it; a guess of (0, 0, 0) would end 6 m off."""
    pair = SimPair(start=(6.0, 0.0))
    pair.drop_to_bridge = lambda msg: msg.get_type() == "HOME_POSITION"
    assert pair.run(5.0, until=lambda: pair.core.connected and pair.core.pose() is not None)
    assert pair.call(flight.takeoff_to, TakeoffRequest(height=3.0)).success
    assert not pair.core.missions.home_known
    op = pair.core.start(
        actions.goto_point(pair.core, GotoRequest(x=2.0, y=0.0, z=3.0)), pair.t, EPOCH + pair.t
    )
    pair.run(2.0)
    assert not op.done and abs(pair.position[0] - 6.0) < 0.5  # waiting, not flying a guess
    pair.drop_to_bridge = lambda msg: False
    assert pair.run(30.0, until=lambda: op.done)
    assert op.result().success, op.result().message
    error = math.dist(pair.position, (8.0, 0.0, 3.0))
    print(f"\ngoto after home arrived: {error:.2f} m from the point (ground truth)")
    assert error <= 1.0


def test_goto_without_home_fails_no_home_and_does_not_move():
    pair = SimPair(start=(6.0, 0.0))
    pair.drop_to_bridge = lambda msg: msg.get_type() == "HOME_POSITION"
    assert pair.run(5.0, until=lambda: pair.core.connected and pair.core.pose() is not None)
    assert pair.call(flight.takeoff_to, TakeoffRequest(height=3.0)).success
    start = pair.t
    reply = pair.call(actions.goto_point, GotoRequest(x=2.0, y=0.0, z=3.0))
    assert reply.failure == NO_HOME and "home is not known after 5 s" in reply.message
    assert pair.t - start <= 5.5
    assert abs(pair.position[0] - 6.0) < 0.5


def test_goto_on_the_ground_is_refused_at_once_naming_goto():
    pair = SimPair()
    pair.connect()
    start = pair.t
    reply = pair.call(actions.goto_point, GotoRequest(x=2.0, y=0.0, z=3.0))
    assert reply.failure == REFUSED and reply.message == "goto refused: not flying (take off first)"
    assert pair.t - start < 0.1 and not pair.autopilot.armed


def test_mission_calls_on_the_ground_with_nothing_to_do_are_refused_without_a_mode_change():
    pair = SimPair()
    pair.connect()
    mode = pair.autopilot.mode.name
    commands = []
    pair.drop_to_autopilot = lambda msg: (
        msg.get_type() == "COMMAND_LONG" and bool(commands.append(msg.command))
    )
    for action, reason in (
        ("start", "no mission uploaded"),
        ("resume", "no mission uploaded"),
        ("pause", "no mission is being flown"),
    ):
        reply = pair.call(actions.mission_action, MissionRequest(action=action))
        assert reply.failure == REFUSED and reason in reply.message, reply.message
    reply = pair.call(actions.return_home, ReturnRequest())
    assert reply.failure == REFUSED and "not flying" in reply.message
    pair.run(2.0)
    assert pair.autopilot.mode.name == mode and not pair.autopilot.armed
    assert [c for c in commands if c != 511] == []  # no mode change, no return was sent


def test_a_take_off_timeout_stops_the_climb():
    pair = SimPair()
    pair.connect()
    reply = pair.call(flight.takeoff_to, TakeoffRequest(height=30.0, timeout=4.0))
    assert reply.failure == TOO_LATE, reply.message
    at_timeout = pair.position[2]
    pair.run(6.0)
    print(f"\ntake-off timeout at {at_timeout:.2f} m; 6 s later {pair.position[2]:.2f} m")
    assert pair.position[2] < at_timeout + 1.5  # braking, not climbing on to 30 m


def fly_local_mission(pair: SimPair, points: list[tuple[float, float, float]]) -> float:
    pair.take_off(3.0)
    push = WaypointPush(waypoints=waypoints_of(points, frame="local"))
    reply = pair.call(missions.push, push)
    assert reply.success, reply.message
    start = pair.t
    reply = pair.call(actions.mission_action, MissionRequest(action="start", watch=APP))
    assert reply.success, reply.message
    return start


def test_a_local_frame_mission_visits_each_item_within_1_m():
    pair = SimPair()
    points = [(3.0, 0.0, 3.0), (3.0, 3.0, 3.0), (0.0, 0.0, 3.0)]
    start = fly_local_mission(pair, points)
    assert pair.run(60.0, until=lambda: pair.core.missions.last_reached == len(points) - 1)
    for point in points:
        approach = pair.closest_approach(point, start)
        print(f"\nlocal mission: {point} within {approach:.2f} m")
        assert approach <= 1.0


def test_a_mission_whose_commander_died_finishes_then_returns_and_lands():
    pair = SimPair(params=dict(FAST_RTL, RTL_RETURN_ALT=6.0))
    alive = {APP}
    pair.alive = lambda: set(alive)
    points = [(10.0, 0.0, 3.0), (10.0, 10.0, 3.0)]
    fly_local_mission(pair, points)
    pair.run(3.0)
    alive.clear()  # Ctrl-C: the app's session, and its liveliness token, are gone
    died = pair.t
    assert pair.run(120.0, until=lambda: not pair.autopilot.armed), (
        f"still flying: {pair.autopilot.mode.name} at {pair.position}"
    )
    assert pair.core.missions.last_reached == 1  # the mission was finished first
    texts = [m.text for m in pair.published(registry.STATUSTEXT, died)]
    assert any("has been gone" in t and ": return" in t for t in texts), texts
    print(f"\ncommander died: on the ground at home {pair.t - died:.1f} s later")
    assert math.hypot(*pair.position[:2]) < 1.0


def test_a_mission_whose_commander_lives_holds_after_its_end():
    pair = SimPair()
    pair.alive = lambda: {APP}
    points = [(5.0, 0.0, 3.0)]
    fly_local_mission(pair, points)
    assert pair.run(30.0, until=lambda: pair.core.missions.last_reached == 0)
    pair.run(15.0)
    assert pair.autopilot.armed and pair.position[2] > 2.0  # left to its commander


def test_a_second_take_off_elsewhere_moves_home_and_goto_follows_it():
    """Home is where the autopilot armed: after landing 8 m east and taking off again, goto
    (0, 3) is 3 m north of the second take-off point, while local positions keep their
    origin (where the autopilot started)."""
    pair = SimPair()
    pair.take_off(3.0)
    request = GotoRequest(x=8.0, y=0.0, z=3.0, tolerance=0.3)
    assert pair.call(actions.goto_point, request, limit=40.0).success
    assert pair.call(flight.land_here, LandRequest(), limit=60.0).success
    spot = pair.position
    assert pair.call(flight.takeoff_to, TakeoffRequest(height=3.0)).success
    assert math.dist(pair.core.missions.home_local[:2], spot[:2]) < 0.1  # the new home
    request = GotoRequest(x=0.0, y=3.0, z=3.0, tolerance=0.3)
    assert pair.call(actions.goto_point, request, limit=40.0).success
    target = (spot[0], spot[1] + 3.0, 3.0)
    assert math.dist(pair.position, target) <= 0.5  # ground truth: from the new home
    assert math.dist(pair.core.telemetry.position_enu, target) <= 0.5  # the same local origin


def test_a_cancel_ends_a_go_to_and_holds_where_it_is():
    pair = SimPair()
    pair.take_off(3.0)
    op = pair.core.start(
        actions.goto_point(pair.core, GotoRequest(x=30.0, y=0.0, z=3.0)), pair.t, EPOCH + pair.t
    )
    pair.run(3.0)
    assert not op.done
    reply = pair.call(cancel_steps, CancelRequest(reason="test"))
    assert reply.success and "go-to cancelled" in reply.message
    assert op.result().failure == CANCELLED
    x = pair.position[0]
    pair.run(8.0)
    assert abs(pair.position[0] - x) < 3.0 and pair.position[0] < 20.0


def test_a_go_to_that_timed_out_and_lost_its_commander_ends_on_the_ground():
    pair = SimPair(params=dict(FAST_RTL, RTL_RETURN_ALT=6.0), unattended_action="land")
    pair.alive = set  # the commander's beats stop after its request
    pair.take_off(3.0)
    request = GotoRequest(x=40.0, y=0.0, z=3.0, timeout=2.0, watch=APP)
    assert pair.call(actions.goto_point, request).failure == TOO_LATE
    assert pair.run(60.0, until=lambda: not pair.autopilot.armed), pair.autopilot.mode.name
    assert pair.position[0] < 25.0  # it held, then landed: it did not fly on to the point
