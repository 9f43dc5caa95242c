"""A parameter write's echo is matched to the write when reads of the same parameter overlap it.

PARAM_VALUE answers a read and acknowledges a write alike; the bridge's core tells them apart by
the value (the write's echo holds the value written). The rig is the pure core facing a
scripted autopilot over real MAVLink bytes (bridge_core_rig.py), in given time.
"""

from __future__ import annotations

import math

from bridge_core_rig import CoreRig, int_bits
from pymavlink.dialects.v20 import common as mavlink

from dronewrapper.msgs.mavros import ParamGet, ParamSet, ParamValue
from dronewrapper_bridge_mavlink import parameters

REAL32 = mavlink.MAV_PARAM_TYPE_REAL32
INT32 = mavlink.MAV_PARAM_TYPE_INT32
SPEED = "MPC_XY_VEL_MAX"


def rig_knowing(value: float = 12.0, **config) -> CoreRig:
    """A connected PX4 whose SPEED (REAL32) was heard at ``value``."""
    rig = CoreRig(**config).connect()
    rig.param(SPEED, value, REAL32)
    return rig


def test_a_read_answered_after_an_overlapping_write_is_not_the_writes_echo():
    rig = rig_knowing(12.0)
    read = rig.call(parameters.param_get, ParamGet(param_id=SPEED))
    write = rig.call(parameters.param_set, ParamSet(param_id=SPEED, value=ParamValue(real=5.0)))
    assert len(rig.sent_since(-math.inf, "PARAM_SET")) == 1
    rig.now += 0.01
    rig.param(SPEED, 12.0, REAL32)  # the read's answer, queued before the write (ArduPilot)
    assert read.done and read.result().value.real == 12.0
    assert not write.done, "the read's answer is not the write's echo"
    rig.param(SPEED, 5.0, REAL32)  # the write's echo
    assert write.done and write.result().success, write.result().message
    assert write.result().value.real == 5.0


def test_an_echo_before_the_overlapping_reads_answer_completes_the_write_at_once():
    rig = rig_knowing(12.0)
    read = rig.call(parameters.param_get, ParamGet(param_id=SPEED))
    write = rig.call(parameters.param_set, ParamSet(param_id=SPEED, value=ParamValue(real=5.0)))
    rig.now += 0.01
    rig.param(SPEED, 5.0, REAL32)
    assert write.done and write.result().success
    assert read.done and read.result().value.real == 5.0  # answered after it was asked
    rig.param(SPEED, 12.0, REAL32)  # a late duplicate changes neither reply
    assert write.result().success and read.result().value.real == 5.0


def test_overlapping_writes_each_take_their_own_echo():
    rig = CoreRig().connect()
    rig.param("COM_RC_IN_MODE", int_bits(1), INT32)
    first = rig.call(
        parameters.param_set, ParamSet(param_id="COM_RC_IN_MODE", value=ParamValue(integer=2))
    )
    second = rig.call(
        parameters.param_set, ParamSet(param_id="COM_RC_IN_MODE", value=ParamValue(integer=3))
    )
    rig.now += 0.01
    rig.param("COM_RC_IN_MODE", int_bits(3), INT32)  # echoes in either order
    rig.param("COM_RC_IN_MODE", int_bits(2), INT32)
    assert first.result().success and first.result().value.integer == 2
    assert second.result().success and second.result().value.integer == 3


def test_an_echo_within_float32_rounding_is_the_writes_echo():
    rig = rig_knowing(12.0)
    write = rig.call(parameters.param_set, ParamSet(param_id=SPEED, value=ParamValue(real=0.1)))
    rig.now += 0.01
    rig.param(SPEED, 0.1, REAL32)  # 0.1 as float32 on the wire: 0.10000000149
    assert write.done and write.result().success


def test_a_write_answered_only_by_another_value_resends_then_reports_the_value_kept():
    rig = rig_knowing(12.0, param_attempts=3, param_timeout=0.5)
    write = rig.call(parameters.param_set, ParamSet(param_id=SPEED, value=ParamValue(real=5.0)))
    rig.now += 0.01
    rig.param(SPEED, 12.0, REAL32)  # the autopilot keeps its value
    assert not write.done
    rig.run(0.6)
    rig.param(SPEED, 12.0, REAL32)
    rig.run(1.0)
    assert write.done and not write.result().success
    assert write.result().message == "the autopilot kept a different value"
    assert write.result().value.real == 12.0
    assert len(rig.sent_since(-math.inf, "PARAM_SET")) == 3


def test_a_write_with_no_answer_at_all_reports_no_echo():
    rig = rig_knowing(12.0, param_attempts=2, param_timeout=0.5)
    write = rig.call(parameters.param_set, ParamSet(param_id=SPEED, value=ParamValue(real=5.0)))
    rig.run(1.2)
    assert write.done and not write.result().success
    assert "no PARAM_VALUE echo" in write.result().message


def test_a_late_echo_of_an_earlier_attempt_still_answers_the_write():
    rig = rig_knowing(12.0, param_attempts=3, param_timeout=0.5)
    write = rig.call(parameters.param_set, ParamSet(param_id=SPEED, value=ParamValue(real=5.0)))
    rig.run(0.6)  # a second PARAM_SET went out
    assert len(rig.sent_since(-math.inf, "PARAM_SET")) == 2
    rig.param(SPEED, 5.0, REAL32)
    assert write.done and write.result().success
