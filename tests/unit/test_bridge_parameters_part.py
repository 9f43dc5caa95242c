"""The MAVLink bridge's parameters as a part of their own (parameters.Parameters): driven on the
few things of a core it uses (its time, the autopilot's kind and address, the outbox), with
real PARAM_VALUE messages; no core needed."""

from __future__ import annotations

import struct

from pymavlink.dialects.v20 import common as mavlink

from dronewrapper.msgs.mavros import ParamGet, ParamSet, ParamValue
from dronewrapper_bridge_mavlink.outgoing import ParamRequestRead, Send
from dronewrapper_bridge_mavlink.outgoing import ParamSet as ParamSetMessage
from dronewrapper_bridge_mavlink.parameters import Parameters

INT32 = mavlink.MAV_PARAM_TYPE_INT32
REAL32 = mavlink.MAV_PARAM_TYPE_REAL32


class Port:
    """A core's side as a parameter exchange sees it: time, autopilot, outbox."""

    def __init__(self, autopilot: str = "px4") -> None:
        self.now = 0.0
        self.autopilot = autopilot
        self.sent: list[Send] = []

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

    reply = run(part.set(ParamSet(param_id="WP_SPD", value=ParamValue.of(7.5))), port, answer)
    assert port.sent == [ParamSetMessage(1, 1, b"WP_SPD", 7.5, REAL32)] * 2
    assert reply.success and reply.value.as_number() == 7.5


def test_an_unanswered_read_gives_up_after_its_attempts():
    port = Port()
    part = Parameters(port, attempts=2, timeout=0.5)
    reply = run(part.get(ParamGet(param_id="NOPE")), port)
    assert len(port.sent) == 2 and not reply.success
    assert reply.message == "NOPE: no PARAM_VALUE (unknown?)"
