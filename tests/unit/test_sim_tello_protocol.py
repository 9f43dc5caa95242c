"""The simulated Tello's SDK 2.0 state machine, command by command, in simulated time (no
sockets, no clock): replies and their addressees, range checks, blocking moves answered when
finished, rc, auto-landing, emergency, battery, several clients, bad input.

Size: one test per SDK command, in the command table's order, over one protocol rig.
"""

from __future__ import annotations

import math
import re
from dataclasses import replace

import pytest

from dronewrapper_sim.tello.flight import Phase, TelloFlight
from dronewrapper_sim.tello.params import TELLO, TelloEnvelope
from dronewrapper_sim.tello.protocol import Reply, TelloProtocol, arc_through
from dronewrapper_sim.tello.state_string import parse_state

CLIENT = ("127.0.0.1", 40000)
OTHER = ("127.0.0.9", 40001)
DT = 0.01


class Tello:
    """A protocol over a flight model, with a simulated clock."""

    def __init__(
        self, battery_percent: float = 100.0, yaw: float = 0.0, envelope: TelloEnvelope = TELLO
    ) -> None:
        self.flight = TelloFlight(
            start=(0.0, 0.0, yaw), envelope=envelope, battery_percent=battery_percent
        )
        self.protocol = TelloProtocol(self.flight, baro_origin_m=100.0)
        self.now = 0.0

    def send(self, text: str | bytes, sender=CLIENT) -> list[Reply]:
        data = text.encode() if isinstance(text, str) else text
        return self.protocol.handle(data, sender, self.now)

    def ask(self, text: str, sender=CLIENT) -> str:
        """A command answered at once: its reply text (to ``sender``)."""
        replies = self.send(text, sender)
        assert len(replies) == 1, (text, replies)
        assert replies[0].address == sender
        return replies[0].text

    def run(self, seconds: float) -> list[Reply]:
        replies = []
        for _ in range(round(seconds / DT)):
            self.now += DT
            replies += self.protocol.tick(DT, self.now)
        return replies

    def until_reply(self, limit_s: float = 30.0) -> tuple[Reply, float]:
        """Step until a late reply comes; (reply, seconds it took)."""
        start = self.now
        while self.now - start < limit_s:
            self.now += DT
            replies = self.protocol.tick(DT, self.now)
            if replies:
                assert len(replies) == 1
                return replies[0], self.now - start
        raise AssertionError(f"no reply within {limit_s} s")

    def blocking(self, text: str, sender=CLIENT) -> float:
        """A blocking command: nothing at once, ``ok`` to ``sender`` when done; its duration."""
        assert self.send(text, sender) == []
        reply, took = self.until_reply()
        assert reply == Reply("ok", sender), text
        return took

    def airborne(self) -> Tello:
        assert self.ask("command") == "ok"
        self.blocking("takeoff")
        return self

    @property
    def position(self) -> tuple[float, float, float]:
        s = self.flight.state
        return s.x, s.y, s.z


def test_silent_until_command_then_ok():
    t = Tello()
    assert t.send("takeoff") == []  # not in SDK mode: the real drone does not answer
    assert t.send("battery?") == []
    assert t.ask("command") == "ok"
    assert t.protocol.session.client == CLIENT
    assert t.flight.phase is Phase.LANDED


@pytest.mark.parametrize(
    ("command", "pattern"),
    [
        ("battery?", r"100"),
        ("speed?", r"100\.0"),
        ("time?", r"0s"),
        ("height?", r"0dm"),
        ("temp?", r"\d+~\d+C"),
        ("attitude?", r"pitch:0;roll:0;yaw:0;"),
        ("baro?", r"100\.0+"),
        ("tof?", r"100mm"),
        ("acceleration?", r"agx:-?0\.00;agy:-?0\.00;agz:-1000\.00;"),
        ("wifi?", r"\d+"),
        ("sdk?", r"20"),
        ("sn?", r"[0-9A-Z]{14}"),
    ],
)
def test_read_commands(command, pattern):
    t = Tello()
    t.ask("command")
    assert re.fullmatch(pattern, t.ask(command)), command


def test_unknown_command():
    t = Tello()
    t.ask("command")
    assert t.ask("fly away") == "unknown command: fly away"
    assert t.ask("\x00takeoff") == "unknown command: ?takeoff"


@pytest.mark.parametrize(
    "command",
    ["forward 50", "cw 90", "ccw 90", "flip l", "go 50 0 0 50", "curve 100 100 0 200 0 0 30"],
)
def test_flight_commands_on_the_ground_are_refused(command):
    t = Tello()
    t.ask("command")
    assert t.ask(command) == "error Motor stop"
    assert t.flight.phase is Phase.LANDED
    assert t.ask("land") == "error Motor stop"


def test_takeoff_answers_when_hovering_at_about_a_metre():
    t = Tello()
    t.ask("command")
    took = t.blocking("takeoff")
    assert 1.5 < took < 8.0  # spool-up and climb, answered at the end
    assert t.flight.phase is Phase.HOVERING
    assert 0.8 <= t.flight.state.z <= 1.2
    assert 80 <= int(parse_state_of(t)["h"]) <= 120
    assert t.ask("takeoff") == "error"  # already flying


def parse_state_of(t: Tello) -> dict:
    from dronewrapper_sim.tello.state_string import format_state

    return parse_state(format_state(t.protocol))


@pytest.mark.parametrize(
    ("command", "forward", "left", "up"),
    [
        ("forward 50", 0.5, 0.0, 0.0),
        ("back 50", -0.5, 0.0, 0.0),
        ("left 50", 0.0, 0.5, 0.0),
        ("right 50", 0.0, -0.5, 0.0),
        ("up 50", 0.0, 0.0, 0.5),
        ("down 50", 0.0, 0.0, -0.5),
        ("go 60 -40 30 50", 0.6, -0.4, 0.3),
    ],
)
def test_moves_in_the_heading_frame_answer_when_finished(command, forward, left, up):
    yaw = math.radians(30.0)  # heading 30 deg CCW from east: body axes differ from ENU
    t = Tello(yaw=yaw)
    t.airborne()
    t.blocking("up 50")  # room to go down
    x0, y0, z0 = t.position
    took = t.blocking(command)
    dist = math.sqrt(forward**2 + left**2 + up**2)
    speed = 0.5 if command.startswith("go") else 1.0
    assert dist / speed <= took < dist / speed + 4.0  # real timing from the speed
    x, y, z = t.position
    ex = x0 + math.cos(yaw) * forward - math.sin(yaw) * left
    ey = y0 + math.sin(yaw) * forward + math.cos(yaw) * left
    assert math.dist((x, y, z), (ex, ey, z0 + up)) < 0.08


def test_speed_sets_the_move_speed():
    t = Tello().airborne()
    assert t.ask("speed 50") == "ok"
    assert t.ask("speed?") == "50.0"
    assert t.blocking("forward 100") >= 2.0
    assert t.ask("speed 9") == "out of range"
    assert t.ask("speed 101") == "out of range"
    assert t.ask("speed?") == "50.0"


def test_rotations_and_the_yaw_sign():
    t = Tello().airborne()
    yaw0 = t.flight.state.yaw
    took = t.blocking("cw 90")
    assert took >= 1.0  # 90 deg at 90 deg/s
    assert math.degrees(t.flight.state.yaw - yaw0) == pytest.approx(-90.0, abs=2.5)  # ENU: CW < 0
    assert parse_state_of(t)["yaw"] == pytest.approx(90, abs=3)  # Tello: clockwise > 0
    t.blocking("ccw 180")
    assert parse_state_of(t)["yaw"] == pytest.approx(-90, abs=3)
    t.blocking("cw 360")
    assert parse_state_of(t)["yaw"] == pytest.approx(-90, abs=3)


def test_flip_and_curve():
    t = Tello().airborne()
    x0, y0, z0 = t.position
    assert t.blocking("flip l") >= 1.0
    assert math.dist(t.position, (x0, y0, z0)) < 0.1
    took = t.blocking("curve 100 100 0 200 0 0 30")  # a half circle of radius 1 m
    assert took >= math.pi / 0.3
    assert math.dist(t.position, (x0 + 2.0, y0, z0)) < 0.1  # heading east: forward = +x
    assert t.ask("curve 100 0 0 200 0 0 30") == "error"  # collinear: no arc
    assert t.ask("curve 100 100 0 200 0 0 61") == "out of range"  # curve speed 10..60
    assert t.ask("curve 10 10 10 200 0 0 30") == "out of range"  # a point within 20 cm


def test_flip_needs_half_a_battery():
    t = Tello(battery_percent=45).airborne()
    assert t.ask("flip f") == "error"
    assert t.ask("flip x") == "error"


@pytest.mark.parametrize(
    ("command", "reply"),
    [
        ("forward 19", "out of range"),
        ("forward 501", "out of range"),
        ("up 0", "out of range"),
        ("cw 0", "out of range"),
        ("ccw 361", "out of range"),
        ("go 10 10 10 50", "out of range"),
        ("go 600 0 0 50", "out of range"),
        ("go 100 0 0 5", "out of range"),
        ("forward abc", "error"),
        ("forward", "error"),
        ("forward 50 50", "error"),
        ("forward 1e2", "error"),
        ("go 100 0 0", "error"),
        ("takeoff now", "error"),
        ("port 80 11111", "out of range"),
        ("wifi", "error"),
    ],
)
def test_bad_arguments_change_nothing(command, reply):
    t = Tello().airborne()
    before = (t.flight.phase, t.protocol.session.speed, t.protocol.session.video_port)
    assert t.ask(command) == reply
    t.run(0.5)
    assert (t.flight.phase, t.protocol.session.speed, t.protocol.session.video_port) == before
    assert t.flight.phase is Phase.HOVERING


def test_a_command_during_a_move_is_refused_and_stop_hovers():
    t = Tello().airborne()
    assert t.send("forward 300") == []
    t.run(1.0)
    assert t.ask("forward 50") == "error Not joystick"
    assert t.ask("battery?") == "100"  # reads are answered while moving
    assert t.ask("stop") == "ok"
    assert t.run(5.0) == []  # the interrupted move is never answered
    assert t.flight.phase is Phase.HOVERING
    assert abs(t.flight.state.vx) < 0.1
    assert t.position[0] < 2.5


def test_rc_velocities_and_signs_in_enu():
    t = Tello(yaw=math.radians(90.0)).airborne()  # heading north: forward = +y, right = +x
    checks = [
        ("rc 0 100 0 0", lambda s: s.vy > 0.8 and abs(s.vx) < 0.15),  # forward
        ("rc 0 -100 0 0", lambda s: s.vy < -0.8 and abs(s.vx) < 0.15),  # back
        ("rc 100 0 0 0", lambda s: s.vx > 0.8 and abs(s.vy) < 0.15),  # right
        ("rc -100 0 0 0", lambda s: s.vx < -0.8 and abs(s.vy) < 0.15),  # left
        ("rc 0 0 100 0", lambda s: s.vz > 0.8),  # up
        ("rc 0 0 -50 0", lambda s: s.vz < -0.4),  # down
        ("rc 0 0 0 100", lambda s: s.r < math.radians(-80)),  # yaw clockwise: ENU rate < 0
        ("rc 0 0 0 -100", lambda s: s.r > math.radians(80)),
    ]
    for command, check in checks:
        t.blocking("up 50") if t.flight.state.z < 1.0 else None
        assert t.send(command) == []  # rc is never answered
        t.run(2.0)
        assert check(t.flight.state), (command, t.flight.state)
        t.send("rc 0 0 0 0")
        t.run(1.5)
        assert t.flight.phase is Phase.HOVERING
    assert t.send("rc 0 101 0 0") == []  # out of range: ignored
    t.run(1.0)
    assert t.flight.phase is Phase.HOVERING
    vx = t.flight.state.vx
    assert abs(vx) < 0.1
    assert max(t.flight.env.rc_max_xy, 0) == pytest.approx(1.0)  # ~1 m/s at 100


def test_a_flight_of_moves_turns_a_curve_a_flip_and_rc_in_one_sequence():
    """The sequence a client flies after take-off and ``forward 50``, each answered ``ok`` when
    finished, judged in ENU (the process's UDP, its ground truth on Zenoh and one of these
    moves: tests/integration/test_sim_tello.py). Heading east at the start, as in
    beacon_static."""
    t = Tello().airborne()
    assert t.blocking("forward 50") >= 0.5
    p1 = t.position
    t.blocking("up 30")
    assert t.position[2] - p1[2] == pytest.approx(0.3, abs=0.1)
    t.blocking("ccw 90")  # now heading north
    assert parse_state(t.ask("attitude?"))["yaw"] == pytest.approx(-90, abs=3)  # ccw < 0
    assert t.ask("speed 50") == "ok"
    p2 = t.position
    t.blocking("go 50 0 -30 60")  # forward (north) and down
    p3 = t.position
    assert (p3[0] - p2[0], p3[1] - p2[1], p3[2] - p2[2]) == pytest.approx((0, 0.5, -0.3), abs=0.1)
    t.blocking("curve 60 60 0 120 0 0 60")
    p4 = t.position
    assert (p4[0] - p3[0], p4[1] - p3[1]) == pytest.approx((0.0, 1.2), abs=0.15)
    t.blocking("flip b")
    t.blocking("cw 90")  # east again

    def velocity(command: str, seconds: float = 1.5) -> tuple[float, float, float]:
        a = t.position
        assert t.send(command) == []  # rc is never answered
        t.run(seconds)
        b = t.position
        t.send("rc 0 0 0 0")
        t.run(1.0)
        return ((b[0] - a[0]) / seconds, (b[1] - a[1]) / seconds, (b[2] - a[2]) / seconds)

    vx, vy, _ = velocity("rc 0 80 0 0")  # forward = east
    assert vx > 0.3 and abs(vy) < 0.2
    vx, vy, _ = velocity("rc 80 0 0 0")  # right = south
    assert vy < -0.3 and abs(vx) < 0.2
    _, _, vz = velocity("rc 0 0 60 0")  # up
    assert vz > 0.2
    yaw0 = t.flight.state.yaw
    t.send("rc 0 0 0 60")  # clockwise: ENU yaw decreases
    t.run(1.0)
    t.send("rc 0 0 0 0")
    turned = (t.flight.state.yaw - yaw0 + math.pi) % (2 * math.pi) - math.pi
    assert math.degrees(turned) < -20


def test_half_stick_gives_half_speed():
    t = Tello().airborne()
    t.send("rc 0 50 0 0")
    t.run(4.0)
    assert t.flight.state.vx == pytest.approx(0.5, abs=0.05)


def test_auto_land_after_15_s_without_a_command():
    t = Tello().airborne()  # the 15 s count from the end of the take-off
    t.run(14.0)
    assert t.flight.flying
    t.send("battery?")  # any command keeps it up
    t.run(14.0)
    assert t.flight.flying
    t.run(2.0)
    assert t.flight.phase is Phase.LANDING
    assert t.blocking("land") < 5.0  # a land during the auto-landing: ok on the ground
    assert t.flight.phase is Phase.LANDED
    assert t.flight.state.z == pytest.approx(0.0, abs=0.01)


def test_a_configured_auto_land_after_3_s_and_land_on_request():
    """``--set tello.auto_land_s=3`` (the simulator builds its envelope so): a take-off and a
    land are answered, on the ground the state says h 0; a second take-off lands by itself 3 s
    after it finished (the auto-land timeout reaching a running process:
    tests/integration/test_tello_bridge_sim.py)."""
    t = Tello(envelope=replace(TELLO, auto_land_s=3.0)).airborne()
    t.blocking("land")
    assert parse_state_of(t)["h"] == 0
    t.blocking("takeoff")
    started = t.now
    while t.flight.phase is not Phase.LANDING:
        t.run(DT)
        assert t.now - started < 15.0, "no auto-landing"
    assert t.now - started == pytest.approx(3.0, abs=2 * DT)  # from the take-off's end
    while parse_state_of(t)["h"] != 0:
        t.run(DT)
        assert t.now - started < 15.0, "the auto-landing never reached the ground"
    assert t.now - started >= 2.5


def test_rc_keeps_it_flying():
    t = Tello().airborne()
    for _ in range(20):
        t.send("rc 0 0 0 0")
        t.run(1.0)
    assert t.flight.flying


def test_emergency_stops_the_motors_at_once_and_it_falls():
    t = Tello().airborne()
    assert t.ask("emergency") == "ok"
    assert not t.flight.motors_on
    t.run(0.1)
    assert t.flight.state.vz < -0.5  # falling
    t.run(1.0)
    assert t.flight.phase is Phase.LANDED
    assert t.flight.state.z == 0.0
    assert t.ask("forward 50") == "error Motor stop"
    assert t.ask("emergency") == "ok"  # on the ground too


def test_land_is_answered_on_the_ground():
    t = Tello().airborne()
    took = t.blocking("land")
    assert took >= 1.0
    assert t.flight.phase is Phase.LANDED
    assert parse_state_of(t)["h"] == 0


def test_low_battery_refuses_takeoff_and_battery_drains():
    t = Tello(battery_percent=9)
    t.ask("command")
    assert t.ask("takeoff") == "error Motor stop"
    assert t.flight.phase is Phase.LANDED
    t = Tello(battery_percent=60).airborne()
    for _ in range(12):  # a minute of hovering costs a few percent (13 min on a full pack)
        t.send("rc 0 0 0 0")
        t.run(5.0)
    assert 50 <= int(t.ask("battery?")) <= 57


def test_lands_by_itself_on_an_empty_battery():
    t = Tello(battery_percent=12).airborne()
    for _ in range(120):
        t.send("rc 0 0 0 0")
        t.run(1.0)
        if not t.flight.flying:
            break
    assert t.flight.phase in (Phase.LANDING, Phase.LANDED)
    assert int(t.ask("battery?")) <= 5


def test_a_second_client_is_obeyed_and_answered():
    t = Tello().airborne()
    took = t.blocking("forward 50", sender=OTHER)  # without 'command' from it
    assert took > 0.5
    assert t.protocol.session.client == CLIENT  # state still goes to the first
    assert t.ask("command", sender=OTHER) == "ok"
    assert t.protocol.session.client == OTHER  # now to the second


def test_port_and_stream_commands():
    t = Tello()
    t.ask("command")
    assert t.ask("streamon") == "ok"
    assert t.protocol.session.streaming
    assert t.ask("port 9000 9001") == "ok"
    assert (t.protocol.session.state_port, t.protocol.session.video_port) == (9000, 9001)
    assert t.ask("streamoff") == "ok"
    assert not t.protocol.session.streaming
    assert t.ask("wifi tello-sim secret") == "ok"


@pytest.mark.parametrize("data", [b"\xff\xfe\xfd", b"takeoff\xff", b"x" * 2000, b"\xc3\x28 50"])
def test_bad_bytes_are_answered_error_and_change_nothing(data):
    t = Tello().airborne()
    assert t.send(data) == [Reply("error", CLIENT)]
    t.run(0.5)
    assert t.flight.phase is Phase.HOVERING


@pytest.mark.parametrize("data", [b"", b"   ", b"\r\n"])
def test_empty_datagrams_are_ignored(data):
    t = Tello()
    t.ask("command")
    assert t.send(data) == []


def test_a_flood_of_garbage_changes_nothing():
    t = Tello().airborne()
    x0 = t.position
    for i in range(2000):
        replies = t.send(bytes([i % 256]) * (i % 40 + 1))
        assert len(replies) <= 1
    t.run(1.0)
    assert t.flight.phase is Phase.HOVERING
    assert math.dist(t.position, x0) < 0.05


def test_arc_through_three_points():
    arc = arc_through((0, 0, 0), (1, 1, 0), (2, 0, 0))
    assert arc is not None
    assert arc[0] == pytest.approx((0, 0, 0), abs=1e-9)
    assert arc[-1] == pytest.approx((2, 0, 0), abs=1e-9)
    assert all(math.dist(p, (1, 0, 0)) == pytest.approx(1.0) for p in arc)
    assert max(p[1] for p in arc) == pytest.approx(1.0, abs=0.01)  # through (1, 1): y > 0 side
    assert arc_through((0, 0, 0), (1, 0, 0), (2, 0, 0)) is None  # collinear
    assert arc_through((0, 0, 0), (0.2, 0.2, 0), (0.4, 0, 0)) is None  # radius < 0.5 m
