"""The MAVLink bridge's typed outbox (outgoing.py): every message it sends is one of the
:data:`Send` values, the one encoder makes MAVLink 2 bytes of each with its fields kept, and a
setpoint is validated once, where it enters the core (a bad one refused in the same words)."""

from __future__ import annotations

import dataclasses
import math
import typing

import pytest
from bridge_core_rig import USER, CoreRig, ops, velocity
from pymavlink.dialects.v20 import common as mavlink
from validation_count import count_validations

from dronewrapper.msgs import registry
from dronewrapper.msgs.mavros import CommandTOL, ParamGet
from dronewrapper_bridge_mavlink import outgoing, parameters
from dronewrapper_bridge_mavlink.outgoing import Send, encode
from dronewrapper_bridge_mavlink.setpoints import LocalNedTarget

OFFBOARD = 6 << 16

SAMPLES: list[Send] = [
    outgoing.Heartbeat(6, 8, 0, 0, 4),
    outgoing.CommandLong(1, 1, 22, 2, (0.0, 0.0, 0.0, math.nan, 0.0, 0.0, 3.0)),
    outgoing.SetPositionTargetLocalNed(
        1, 1, 1234, LocalNedTarget(1, 1991, vx=1.5, vy=-0.5, vz=0.25, yaw_rate=0.3)
    ),
    outgoing.ParamRequestRead(1, 1, b"MPC_XY_VEL_MAX"),
    outgoing.ParamSet(1, 1, b"MPC_XY_VEL_MAX", 5.0, 9),
    outgoing.MissionCount(1, 1, 3, 2),
    outgoing.MissionItemInt(1, 1, 2, 3, 16, 0, 1, 0.0, 0.0, 0.0, 0.0, 473977000, 85456000, 10.0, 0),
    outgoing.MissionRequestList(1, 1, 1),
    outgoing.MissionRequestInt(1, 1, 4, 0),
    outgoing.MissionClearAll(1, 1, 2),
    outgoing.MissionAck(1, 1, 0, 0),
]


def test_the_samples_cover_every_message_of_the_union():
    assert {type(s) for s in SAMPLES} == set(typing.get_args(Send))


@pytest.mark.parametrize("message", SAMPLES, ids=lambda m: type(m).__name__)
def test_each_message_survives_a_mavlink2_round_trip_with_its_fields(message):
    tx = mavlink.MAVLink(None, srcSystem=255, srcComponent=191)
    parsed = mavlink.MAVLink(None).parse_char(encode(message).pack(tx))
    fields = dataclasses.asdict(message)
    fields.update(fields.pop("target", {}))  # a setpoint's content
    for name, value in fields.items():
        if name == "params":
            got = tuple(getattr(parsed, f"param{i}") for i in range(1, 8))
            pairs = zip(got, value, strict=True)
            assert all(a == b or (math.isnan(a) and math.isnan(b)) for a, b in pairs)
        elif isinstance(value, bytes):
            assert getattr(parsed, name) == value.decode()
        elif isinstance(value, float):
            assert math.isclose(getattr(parsed, name), value, rel_tol=1e-6)
        else:
            assert getattr(parsed, name) == value, name


def test_messages_are_immutable_values():
    beat = outgoing.Heartbeat(6, 8, 0, 0, 4)
    with pytest.raises(dataclasses.FrozenInstanceError):
        beat.type = 2  # type: ignore[misc]
    assert beat == outgoing.Heartbeat(6, 8, 0, 0, 4)


def test_a_value_outside_the_union_is_refused_by_the_encoder():
    with pytest.raises(TypeError, match="not a message the bridge sends"):
        encode(("heartbeat", (6, 8, 0, 0, 4)))  # type: ignore[arg-type]


def test_everything_the_core_queues_is_a_typed_message():
    """Take-off, a setpoint stream, a parameter read and the ticks: the outbox holds only
    :data:`Send` values, never a message name."""
    rig = CoreRig().connect()
    kinds = typing.get_args(Send)
    queued: list[object] = []
    take = rig.core.take

    def recording_take():
        out = take()
        queued.extend(out.sends)
        return out

    rig.core.take = recording_take  # type: ignore[method-assign]
    rig.call(ops.takeoff, CommandTOL.takeoff(2.0))
    rig.call(parameters.param_get, ParamGet(param_id="MPC_XY_VEL_MAX"))
    rig.run(1.0, stream=True)
    assert queued and all(isinstance(m, kinds) for m in queued)
    assert {type(m) for m in queued} >= {
        outgoing.Heartbeat,
        outgoing.CommandLong,
        outgoing.SetPositionTargetLocalNed,
        outgoing.ParamRequestRead,
    }


def test_a_setpoint_is_validated_once_on_its_way_to_the_autopilot(monkeypatch):
    calls = count_validations(monkeypatch)
    rig = CoreRig().connect(mode=OFFBOARD, armed=True, flying=True)
    before = len(rig.setpoints())
    rig.setpoint(velocity(1.0))
    assert len(rig.setpoints()) == before + 1  # sent at once
    assert len(calls) == 1


def test_a_bad_setpoint_is_refused_at_the_edge_in_the_shared_words():
    rig = CoreRig().connect(mode=OFFBOARD, armed=True, flying=True)
    rig.setpoint(velocity(math.nan))
    rig.setpoint(velocity(99.0))
    refusals = rig.published(registry.REFUSAL)
    assert [(r.kind, r.limit, r.message, r.commander) for r in refusals] == [
        ("validation", "velocity.x", "velocity.x must be a finite number, got nan", USER),
        ("validation", "max_horizontal_speed", "horizontal speed 99 m/s exceeds 20", USER),
    ]
    assert rig.setpoints() == [] and rig.core.rejected_setpoints == 2
