"""bridge_mavlink's take-off and landing operations, against a scripted autopilot in given time.

The autopilot (:class:`Autopilot`) answers every command as PX4 or ArduPilot does (PX4's
DO_SET_MODE twice), flies toward the streamed position setpoint (PX4 in OFFBOARD) or its
NAV_TAKEOFF altitude (ArduPilot), descends after NAV_LAND and disarms on the ground. Real
MAVLink bytes both ways (bridge_core_rig.py).
"""

from __future__ import annotations

import pytest
from bridge_core_rig import (
    ACCEPTED,
    ARDU_GUIDED,
    ARDUPILOT,
    ARM,
    AUTO_LAND,
    NAV_LAND,
    NAV_TAKEOFF,
    OFFBOARD,
    REJECTED,
    SET_MODE,
    CoreRig,
    velocity,
)
from pymavlink.dialects.v20 import common as mavlink

from dronewrapper.envelope import Envelope
from dronewrapper.msgs.flight import (
    CANCELLED,
    NO_POSITION,
    NOT_READY,
    REFUSED,
    TOO_LATE,
    CancelRequest,
    LandRequest,
    TakeoffRequest,
)
from dronewrapper_bridge_base.core_driver import cancel_steps
from dronewrapper_bridge_mavlink import flight

ON_GROUND, IN_AIR = mavlink.MAV_LANDED_STATE_ON_GROUND, mavlink.MAV_LANDED_STATE_IN_AIR
DT = 0.05


class Autopilot:
    """Plays the autopilot for ``rig``: answers commands (``refuse``: command -> result),
    climbs or sinks at ``rate`` m/s, publishes its pose and landed state every step."""

    def __init__(self, rig: CoreRig, *, rate: float = 1.0, refuse: dict | None = None) -> None:
        self.rig, self.rate, self.refuse = rig, rate, refuse or {}
        self.z = self.goal = 0.0
        self.landing = False
        self._answered = 0
        self.px4 = rig.autopilot != ARDUPILOT

    def answer(self) -> None:
        rig = self.rig
        commands = rig.sent_since(-1.0, "COMMAND_LONG")
        for cmd in commands[self._answered :]:
            result = self.refuse.get(cmd.command, ACCEPTED)
            if result == ACCEPTED:
                if cmd.command == SET_MODE:
                    rig.custom_mode = (
                        int(cmd.param2) << 16 | int(cmd.param3) << 24
                        if self.px4
                        else int(cmd.param2)
                    )
                elif cmd.command == ARM:
                    rig.armed = cmd.param1 == 1.0
                elif cmd.command == NAV_TAKEOFF:
                    self.goal = cmd.param7
                elif cmd.command == NAV_LAND:
                    rig.custom_mode = AUTO_LAND if self.px4 else 9
                    self.landing = True
            rig.ack(cmd.command, result)
            if cmd.command == SET_MODE and self.px4:
                rig.ack(cmd.command, result)  # PX4's second ack: the commander's answer
        self._answered = len(commands)

    def fly(self) -> None:
        rig = self.rig
        if self.px4 and rig.custom_mode == OFFBOARD and rig.armed:
            streamed = rig.setpoints(since=rig.now - 0.5)
            if streamed:
                self.goal = -streamed[-1].z
        if self.landing:
            self.goal = 0.0
        if rig.armed:
            step = self.rate * DT
            self.z += max(-step, min(step, self.goal - self.z))
        if self.landing and self.z <= 0.05:
            self.z, rig.armed, self.landing = 0.0, False, False
        rig.pose(down=-self.z)
        rig.landed(IN_AIR if self.z > 0.1 else ON_GROUND)

    def run(self, op, limit: float = 60.0):
        end = self.rig.now + limit
        while not op.done and self.rig.now < end:
            self.answer()
            self.rig.run(DT)
            self.fly()
        assert op.done, f"{op.name} still running after {limit} s"
        return op.result()


def grounded(**config) -> tuple[CoreRig, Autopilot]:
    autopilot = config.pop("autopilot", None)
    rig = CoreRig(**config) if autopilot is None else CoreRig(autopilot=autopilot, **config)
    rig.connect()
    return rig, Autopilot(rig)


def test_px4_takes_off_on_its_own_stream_and_holds_there_without_a_commander():
    rig, ap = grounded(commander_lost_timeout=2.0)
    reply = ap.run(rig.call(flight.takeoff_to, TakeoffRequest(height=2.0)))
    assert reply.success and reply.height == pytest.approx(2.0, abs=0.1), reply
    assert [c.command for c in rig.sent_since(-1.0, "COMMAND_LONG") if c.command != 511] == [
        SET_MODE,
        ARM,
    ]
    streamed = rig.setpoints()
    assert -streamed[0].z == pytest.approx(0.0) and -streamed[-1].z == pytest.approx(2.0)
    done = rig.now
    for _ in range(int(8.0 / DT)):  # nobody commands: the bridge holds 2 m in OFFBOARD
        rig.run(DT)
        ap.fly()
    assert rig.core.current_state().mode == "OFFBOARD" and rig.core.failsafe.state == ""
    assert rig.commands(NAV_LAND) == [] and ap.z == pytest.approx(2.0, abs=0.05)
    times = [t for t, m in rig.sent if t > done and m.get_type() == "SET_POSITION_TARGET_LOCAL_NED"]
    assert max(b - a for a, b in zip([done, *times], times, strict=False)) <= 2 * DT
    rig.setpoint(velocity(1.0))  # a commander steers: the bridge's own hold ends
    assert rig.core.failsafe.engaged and rig.core.failsafe.fresh_target(rig.now) is not None


def test_ardupilot_takes_off_with_guided_arm_and_nav_takeoff():
    rig, ap = grounded(autopilot=ARDUPILOT)
    rig.custom_mode = 5
    reply = ap.run(rig.call(flight.takeoff_to, TakeoffRequest(height=3.0)))
    assert reply.success, reply
    commands = [c for c in rig.sent_since(-1.0, "COMMAND_LONG") if c.command != 511]
    assert [c.command for c in commands] == [SET_MODE, ARM, NAV_TAKEOFF]
    assert commands[0].param2 == ARDU_GUIDED and commands[2].param7 == 3.0
    assert rig.setpoints() == []  # its own take-off: never a position target over it


def test_a_refused_step_is_named_with_its_result_and_the_stream_stops():
    rig, ap = grounded()
    ap.refuse[ARM] = REJECTED
    reply = ap.run(rig.call(flight.takeoff_to, TakeoffRequest(height=2.0)))
    assert (reply.success, reply.failure, reply.step, reply.result) == (
        False,
        REFUSED,
        "arming",
        REJECTED,
    )
    stopped = rig.now
    rig.run(1.0)
    assert rig.setpoints(since=stopped + DT) == []


def test_the_autopilot_giving_up_the_climb_is_a_refusal_with_its_text():
    rig, ap = grounded()
    op = rig.call(flight.takeoff_to, TakeoffRequest(height=5.0))
    while not rig.armed or ap.z < 0.5:
        ap.answer()
        rig.run(DT)
        ap.fly()
    rig.text("Failsafe: battery critical")
    rig.armed = False
    reply = ap.run(op)
    assert reply.failure == REFUSED and reply.step == "takeoff"
    assert reply.message == "the autopilot disarmed (Failsafe: battery critical)"


def test_too_late_names_the_altitude_mode_and_arming():
    rig, ap = grounded()
    ap.rate = 0.1
    reply = ap.run(rig.call(flight.takeoff_to, TakeoffRequest(height=5.0, timeout=3.0)))
    assert reply.failure == TOO_LATE
    assert "altitude 5.00 m not reached within 3 s (now z=0." in reply.message
    assert "mode OFFBOARD, armed True" in reply.message


def test_already_flying_sends_nothing_and_nothing_without_a_link_or_a_position():
    rig = CoreRig().connect(mode=OFFBOARD, armed=True, flying=True)
    reply = rig.call(flight.takeoff_to, TakeoffRequest(height=2.0)).result()
    assert reply.success and reply.message.startswith("already flying (z=5.00 m)")
    assert rig.sent_since(-1.0, "COMMAND_LONG") == [] or all(
        c.command == 511 for c in rig.sent_since(-1.0, "COMMAND_LONG")
    )
    fresh = CoreRig()
    assert fresh.call(flight.takeoff_to, TakeoffRequest(height=2.0)).result().failure == NOT_READY
    fresh.heartbeat()
    assert fresh.call(flight.takeoff_to, TakeoffRequest(height=2.0)).result().failure == NO_POSITION


@pytest.mark.parametrize(
    "request_",
    [
        TakeoffRequest(height=0.0),
        TakeoffRequest(height=float("nan")),
        TakeoffRequest(height=2.0, timeout=float("inf")),
        TakeoffRequest(height=2.0, tolerance=2.0),
    ],
)
def test_a_bad_take_off_request_is_refused_before_anything_is_sent(request_):
    rig = CoreRig().connect()
    with pytest.raises(ValueError):
        rig.call(flight.takeoff_to, request_).result()


def test_landing_waits_until_on_the_ground_and_disarmed():
    rig, ap = grounded()
    assert ap.run(rig.call(flight.takeoff_to, TakeoffRequest(height=2.0))).success
    start = rig.now
    reply = ap.run(rig.call(flight.land_here, LandRequest()))
    assert reply.success and reply.message == "on the ground and disarmed"
    assert rig.now - start >= 1.9  # 2 m at 1 m/s
    assert not rig.armed and len(rig.commands(NAV_LAND)) == 1
    again = rig.call(flight.land_here, LandRequest()).result()
    assert again.success and again.message == "already on the ground and disarmed"


def test_a_refused_landing_is_named():
    rig, ap = grounded()
    assert ap.run(rig.call(flight.takeoff_to, TakeoffRequest(height=2.0))).success
    ap.refuse[NAV_LAND] = REJECTED
    reply = ap.run(rig.call(flight.land_here, LandRequest()))
    assert (reply.failure, reply.step, reply.result) == (REFUSED, "land", REJECTED)


def test_a_take_off_above_the_envelope_is_refused_before_anything_is_sent():
    rig, ap = grounded(envelope=Envelope(max_altitude=10.0))
    reply = ap.run(rig.call(flight.takeoff_to, TakeoffRequest(height=12.0)))
    assert (reply.success, reply.failure, reply.step) == (False, REFUSED, "takeoff")
    assert "12 m above the envelope's 10 m" in reply.message
    assert [c for c in rig.sent_since(-1.0, "COMMAND_LONG") if c.command != 511] == []


def climb_to(rig: CoreRig, ap: Autopilot, z: float, limit: float = 20.0) -> None:
    end = rig.now + limit
    while ap.z < z and rig.now < end:
        ap.answer()
        rig.run(DT)
        ap.fly()
    assert ap.z >= z


@pytest.mark.parametrize("autopilot", ["px4", ARDUPILOT])
def test_a_cancel_ends_the_take_off_at_once_and_holds_where_it_is(autopilot):
    rig, ap = grounded() if autopilot == "px4" else grounded(autopilot=ARDUPILOT)
    if autopilot == ARDUPILOT:
        rig.custom_mode = 5
    takeoff = rig.call(flight.takeoff_to, TakeoffRequest(height=3.0))
    climb_to(rig, ap, 1.0)
    cancelled_at, z = rig.now, ap.z
    reply = rig.call(cancel_steps, CancelRequest(reason="the user's cancel")).result()
    assert reply.success and reply.message == "take-off cancelled; holding here"
    assert takeoff.done and takeoff.result().failure == CANCELLED
    assert "the user's cancel" in takeoff.result().message
    for _ in range(round(2.0 / DT)):
        ap.answer()
        rig.run(DT)
        ap.fly()
    held = rig.setpoints(since=cancelled_at)
    assert held and all(-sp.z == pytest.approx(z, abs=0.06) for sp in held)
    if autopilot == "px4":  # the bus autopilot follows the hold: the climb stopped
        assert ap.z == pytest.approx(z, abs=0.06)
    nothing = rig.call(cancel_steps, CancelRequest()).result()
    assert not nothing.success and "nothing to cancel" in nothing.message


def test_a_cancelled_landing_holds_in_offboard():
    rig, ap = grounded()
    ap.run(rig.call(flight.takeoff_to, TakeoffRequest(height=2.0)))
    landing = rig.call(flight.land_here, LandRequest())
    for _ in range(round(0.6 / DT)):
        ap.answer()
        rig.run(DT)
        ap.fly()
    z = ap.z
    assert 1.0 < z < 1.9
    cancelled_at = rig.now
    rig.call(cancel_steps, CancelRequest())
    assert landing.done and landing.result().failure == CANCELLED
    for _ in range(round(2.0 / DT)):
        ap.answer()
        rig.run(DT)
        ap.fly()
    assert rig.commands(SET_MODE, since=cancelled_at), "OFFBOARD was not asked for"
    assert rig.custom_mode == OFFBOARD  # the bus autopilot entered it
    held = rig.setpoints(since=cancelled_at)
    assert held and all(-sp.z == pytest.approx(z, abs=0.06) for sp in held)
