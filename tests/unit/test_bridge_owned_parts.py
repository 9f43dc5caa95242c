"""The bridges' parts that own their state, each driven on the few things of a core it uses
(its time, the autopilot's kind and address, the outbox), with real MAVLink messages and no
core: the MAVLink bridge's parameters (parameters.Parameters), mission transfers
(transfers.Transfers) and commands (command_exchange.Commands), and the envelope and home both
PX4-capable bridges hold (bridge_base's envelope_state.EnvelopeState), and the mission state
each bridge keeps (mission_state.MissionState, the Tello's TelloMissions) making its own
changes."""

from __future__ import annotations

import math
import struct

import pytest
from pymavlink.dialects.v20 import common as mavlink

from dronewrapper.envelope import Envelope
from dronewrapper.msgs.mavros import ParamGet, ParamSet, StatusText
from dronewrapper.msgs.mission import Waypoint
from dronewrapper.runtime import ServiceError
from dronewrapper_bridge_base.envelope_state import PUBLISH_PERIOD_S, EnvelopeState
from dronewrapper_bridge_mavlink.command_exchange import Commands
from dronewrapper_bridge_mavlink.config import Config
from dronewrapper_bridge_mavlink.mission_state import MissionState
from dronewrapper_bridge_mavlink.mission_transfer import FENCE, Item
from dronewrapper_bridge_mavlink.outgoing import (
    CommandLong,
    MissionClearAll,
    MissionCount,
    MissionItemInt,
    ParamRequestRead,
    Send,
)
from dronewrapper_bridge_mavlink.outgoing import ParamSet as ParamSetMessage
from dronewrapper_bridge_mavlink.parameters import Parameters
from dronewrapper_bridge_mavlink.transfers import Transfers
from dronewrapper_bridge_tello.mission_state import TelloMissions

INT32 = mavlink.MAV_PARAM_TYPE_INT32
REAL32 = mavlink.MAV_PARAM_TYPE_REAL32


class Port:
    """A core's side as its parts see it: time, autopilot, outbox, command slot, texts."""

    def __init__(self, autopilot: str = "px4") -> None:
        self.now = 0.0
        self.autopilot = autopilot
        self.sent: list[Send] = []
        self.command_busy = False
        self.recent_texts: list[tuple[float, StatusText]] = []

    def take_command_slot(self) -> None:
        self.command_busy = True

    def release_command_slot(self) -> None:
        self.command_busy = False

    def target(self) -> tuple[int, int]:
        return (1, 1)

    def send(self, message: Send) -> None:
        self.sent.append(message)

    def require_connected(self) -> str:
        return self.autopilot


def value(name: str, raw: float, param_type: int) -> mavlink.MAVLink_param_value_message:
    return mavlink.MAVLink_param_value_message(name.encode(), raw, param_type, 1, 0)


def int_bits(n: int) -> float:
    return struct.unpack("<f", struct.pack("<i", n))[0]


def run(steps, port: Port, answer=None):
    """Drive ``steps`` to its end, ``answer(part)`` called after each send (time moves on)."""
    try:
        wake = next(steps)
        while True:
            if answer is not None:
                answer()
            port.now = wake
            wake = steps.send(None)
    except StopIteration as stop:
        return stop.value


def test_a_read_sends_a_typed_request_and_takes_the_value_heard_after_it():
    port = Port()
    part = Parameters(port, attempts=3, timeout=0.5)
    part.on_value(value("COM_RC_IN_MODE", int_bits(4), INT32))  # before the request: not it
    steps = part.get(ParamGet(param_id="COM_RC_IN_MODE"))
    reply = run(steps, port, lambda: part.on_value(value("COM_RC_IN_MODE", int_bits(1), INT32)))
    assert port.sent == [ParamRequestRead(1, 1, b"COM_RC_IN_MODE")]
    assert reply.success and reply.value.as_number() == 1


def test_a_write_re_sends_until_its_echo_and_reports_it():
    port = Port(autopilot="ardupilotmega")
    part = Parameters(port, attempts=3, timeout=0.5)
    part.on_value(value("WP_SPD", 5.0, REAL32))
    echoes = iter([None, 7.5])  # the first send is lost

    def answer():
        echoed = next(echoes, None)
        if echoed is not None:
            part.on_value(value("WP_SPD", echoed, REAL32))

    reply = run(part.set(ParamSet.of("WP_SPD", 7.5)), port, answer)
    assert port.sent == [ParamSetMessage(1, 1, b"WP_SPD", 7.5, REAL32)] * 2
    assert reply.success and reply.value.as_number() == 7.5


def test_an_unanswered_read_gives_up_after_its_attempts():
    port = Port()
    part = Parameters(port, attempts=2, timeout=0.5)
    reply = run(part.get(ParamGet(param_id="NOPE")), port)
    assert len(port.sent) == 2 and not reply.success
    assert reply.message == "NOPE: no PARAM_VALUE (unknown?)"


def ack(mission_type: int = 0) -> mavlink.MAVLink_mission_ack_message:
    return mavlink.MAVLink_mission_ack_message(255, 191, mavlink.MAV_MISSION_ACCEPTED, mission_type)


def test_transfers_run_one_at_a_time_each_made_when_its_turn_comes():
    port = Port()
    part = Transfers(port, timeout=1.0, attempts=3)
    fence = part.upload([Item(frame=0, command=5003, x=1, y=2)], mission_type=FENCE)
    clear = part.clear()
    assert next(fence) == 1.0  # the count sent, its answer awaited
    port.now = 2.5  # the clear waited longer than a timeout for its turn
    assert next(clear) == 2.5 + 0.05
    part.on_message(mavlink.MAVLink_mission_request_int_message(255, 191, 0, FENCE))
    assert fence.send(None) == 3.5
    part.on_message(ack(FENCE))
    try:
        fence.send(None)
    except StopIteration as stop:
        assert stop.value.done and not stop.value.error
    port.now = 2.6
    assert clear.send(None) == 3.6  # its turn: made now, sent once (no re-send for the wait)
    assert [type(m) for m in port.sent] == [MissionCount, MissionItemInt, MissionClearAll]
    assert port.sent[-1] == MissionClearAll(1, 1, 0)


def test_the_envelope_declares_a_breach_once_per_excursion_and_only_in_flight():
    state = EnvelopeState(Envelope(max_distance=10.0, margin=1.0, breach_action="land"))
    state.home_local = (5.0, 0.0, 0.0)  # the envelope is measured from home
    assert state.watch((20.0, 0.0, 2.0), flying=False) == ""  # on the ground: nothing
    assert (
        state.watch((20.0, 0.0, 2.0), flying=True)
        == "distance 15 m from home beyond the envelope's 10 m"
    )
    assert state.monitor.limit == "max_distance" and state.breach_state() == "breach:land"
    assert state.watch((21.0, 0.0, 2.0), flying=True) == ""  # the same excursion
    assert state.watch((14.0, 0.0, 2.0), flying=True) == ""  # 9 m from home: back inside
    assert state.breach_state() == "" and state.watch((20.0, 0.0, 2.0), flying=True)


def test_the_envelope_refuses_a_guided_mode_only_while_outside_and_a_high_takeoff():
    state = EnvelopeState(Envelope(max_altitude=20.0))
    state.refuse_mode("OFFBOARD", guided=True)  # inside: allowed
    state.watch((0.0, 0.0, 30.0), flying=True)
    state.refuse_mode("AUTO.LAND", guided=False)
    with pytest.raises(ServiceError, match="OFFBOARD refused: the aircraft is outside"):
        state.refuse_mode("OFFBOARD", guided=True)
    with pytest.raises(ServiceError, match="20"):
        state.refuse_takeoff(25.0)


def test_home_is_published_without_a_geodetic_position_until_one_is_known():
    state = EnvelopeState(Envelope())
    state.home_local = (1.0, 2.0, 3.0)
    home = state.home_message(1.7e9)
    assert math.isnan(home.latitude) and (home.x, home.y, home.z) == (1.0, 2.0, 3.0)
    state.home_geo = (47.4, 8.5, 400.0)
    assert state.home_message(1.7e9).latitude == 47.4


def test_a_command_is_re_sent_until_acked_and_a_refusal_gives_the_autopilots_words():
    port = Port()
    config = Config(command_attempts=3, command_ack_timeout=0.5, reason_wait=1.0)
    part = Commands(port, config)
    arm = mavlink.MAV_CMD_COMPONENT_ARM_DISARM

    def answer():
        if len(port.sent) == 2 and port.command_busy:  # the second send is answered
            port.recent_texts.append((port.now, StatusText(severity=4, text="Arming denied")))
            part.on_ack(arm, mavlink.MAV_RESULT_DENIED)

    pending, message = run(part.exchange(arm, 1.0), port, answer)
    confirmations = [m.confirmation for m in port.sent if isinstance(m, CommandLong)]
    assert confirmations == [0, 1] and not port.command_busy
    assert pending.result == mavlink.MAV_RESULT_DENIED
    assert message == "COMPONENT_ARM_DISARM refused: DENIED (Arming denied)"


@pytest.mark.parametrize(
    "make", [lambda: EnvelopeState(Envelope()), lambda: TelloMissions(Envelope())]
)
def test_envelope_and_home_are_published_again_once_a_period(make):
    state = make()
    assert state.publish_due(10.0)  # the first tick publishes
    assert not state.publish_due(10.0 + PUBLISH_PERIOD_S - 0.01)
    assert state.publish_due(10.0 + PUBLISH_PERIOD_S)
    assert not state.publish_due(10.0 + PUBLISH_PERIOD_S)


def test_the_mission_state_makes_its_own_changes():
    state = MissionState(Envelope())
    items = [Waypoint(x_lat=47.0 + i, y_long=8.0, z_alt=10.0) for i in range(3)]
    state.new_mission(items)
    assert state.on_current(1) and state.on_reached(0)
    listing = state.listing(1.7e9)
    assert listing.current_seq == 1 and listing.header.stamp == 1.7e9
    assert [wp.is_current for wp in listing.waypoints] == [False, True, False]
    state.downloaded(items[:2])  # a download keeps the item being flown
    assert state.waypoints == items[:2] and state.current_seq == 1
    state.started()
    assert state.last_reached == -1 and state.on_reached(0)
    state.cleared()
    assert state.waypoints == [] and state.current_seq == 0


def test_the_tello_mission_is_kept_flown_from_its_first_item():
    state = TelloMissions(Envelope())
    state.current_seq = 2
    state.kept([Waypoint(frame=4, x_lat=1.0, y_long=2.0, z_alt=3.0)])
    assert state.current_seq == 0 and len(state.listing(1.0).waypoints) == 1
    assert not state.flying
