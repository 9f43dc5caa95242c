"""One wake-up's messages in one call of the bridge's core (receive.on_batch)."""

from __future__ import annotations

from types import SimpleNamespace

from bridge_core_rig import ADDRESS, EPOCH, CoreRig
from pymavlink.dialects.v20 import common as mavlink

from dronewrapper.msgs import registry
from dronewrapper_bridge_mavlink.receive import on_batch


def received(rig: CoreRig, msg) -> SimpleNamespace:
    """``msg`` as the link hands it over: decoded from the autopilot's bytes, with its source."""
    (decoded,) = rig._decoder.parse_buffer(rig.packed(msg))
    return SimpleNamespace(msg=decoded, source=ADDRESS)


def test_a_batch_is_handled_in_order_at_one_time():
    rig = CoreRig().connect(flying=True)
    rig.core.take()
    batch = [
        received(rig, mavlink.MAVLink_local_position_ned_message(5000 + i, i, 0, -5, 0, 0, 0))
        for i in range(3)
    ]
    on_batch(rig.core, batch, rig.now, EPOCH + rig.now)
    poses = [m for topic, m in rig.core.take().samples if topic == registry.LOCAL_POSE]
    assert [p.pose.position.y for p in poses] == [0.0, 1.0, 2.0]  # north -> ENU y, in order
    assert {p.header.stamp for p in poses} == {EPOCH + rig.now}


class Broken:
    """A message whose handling raises."""

    def get_type(self) -> str:
        raise RuntimeError("unreadable")


def test_a_message_that_raises_is_counted_and_the_others_are_handled():
    rig = CoreRig().connect(flying=True)
    rig.core.take()
    pose = mavlink.MAVLink_local_position_ned_message(6000, 1.0, 0, -5, 0, 0, 0)
    batch = [SimpleNamespace(msg=Broken(), source=ADDRESS), received(rig, pose)]
    on_batch(rig.core, batch, rig.now, EPOCH + rig.now)
    out = rig.core.take()
    assert out.errors == ["mavlink"]
    assert [topic for topic, _ in out.samples].count(registry.LOCAL_POSE) == 1
