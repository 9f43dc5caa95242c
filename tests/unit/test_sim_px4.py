"""The simulated PX4's pure parts: its mode encoding, its parameters and the parsing of
offboard setpoints. The commander: ``test_sim_px4_commander.py``; the autopilot over MAVLink
bytes: ``test_sim_px4_mavlink.py``."""

from __future__ import annotations

import math

import pytest
from pymavlink.dialects.v20 import common as mavlink

from dronewrapper_sim.px4 import modes, offboard, params
from dronewrapper_sim.px4.modes import Mode

# ---- modes and params ----


def test_custom_mode_encoding_matches_px4():
    assert Mode.OFFBOARD.custom_mode == 6 << 16 == 393216
    assert Mode.LOITER.custom_mode == (4 << 16) | (3 << 24) == 50593792
    assert Mode.LAND.custom_mode == (4 << 16) | (6 << 24)
    assert modes.decode(Mode.RTL.custom_mode) == (4, 5)
    assert modes.from_custom_mode(Mode.TAKEOFF.custom_mode) is Mode.TAKEOFF
    assert modes.from_main_sub(6, 7) is Mode.OFFBOARD  # sub ignored outside AUTO
    assert modes.from_main_sub(4, 42) is None
    assert modes.from_name("AUTO.LOITER") is Mode.LOITER
    assert modes.from_name("offboard") is Mode.OFFBOARD
    assert Mode.RTL.mavros_name == "AUTO.RTL"


def test_param_defaults_are_px4s():
    store = params.ParamStore()
    assert store["COM_OF_LOSS_T"] == 1.0
    assert store["COM_OBL_RC_ACT"] == 0
    assert store["NAV_RCL_ACT"] == 2
    assert store["NAV_DLL_ACT"] == 0
    assert store["COM_DISARM_PRFLT"] == 10.0
    assert store["COM_DISARM_LAND"] == 2.0
    assert store["MIS_TAKEOFF_ALT"] == 2.5
    assert store["MPC_XY_VEL_MAX"] == 12.0
    assert store["MPC_Z_VEL_MAX_UP"] == 3.0
    assert store["MPC_TKO_SPEED"] == 1.5
    assert store["COM_RC_IN_MODE"] == 1
    assert store["COM_ARM_WO_GPS"] == 1
    assert len({p.name for p in store.defs}) == len(store)
    assert all(len(p.name) <= 16 for p in store.defs)


def test_int32_params_travel_as_raw_bits():
    store = params.ParamStore()
    wire = store.wire_value("SYS_AUTOSTART")
    assert wire != 10040.0 and wire == pytest.approx(1.4069e-41, rel=1e-3)
    assert params.float_bits_to_int32(wire) == 10040
    assert store.type_of("SYS_AUTOSTART") == mavlink.MAV_PARAM_TYPE_INT32
    assert store.type_of("COM_OF_LOSS_T") == mavlink.MAV_PARAM_TYPE_REAL32
    assert store.wire_value("COM_OF_LOSS_T") == 1.0
    bits = params.int32_to_float_bits(3)
    assert store.from_wire("NAV_RCL_ACT", bits, mavlink.MAV_PARAM_TYPE_INT32) == 3
    with pytest.raises(ValueError):
        store.set("COM_OF_LOSS_T", math.nan)
    with pytest.raises(KeyError):
        store.set("NOT_A_PARAM", 1)


# ---- offboard setpoints ----

ZERO3 = (0.0, 0.0, 0.0)


@pytest.mark.parametrize("frame", [7, 9, 12, 0, 3])
def test_unsupported_frames_are_refused_with_px4s_text(frame):
    result = offboard.parse(frame, 1991, ZERO3, (1.0, 0, 0), ZERO3, 0.0, 0.0, 0.0)
    assert isinstance(result, offboard.Refusal)
    assert result.statustext == (
        f"SET_POSITION_TARGET_LOCAL_NED coordinate frame {frame} unsupported"
    )


def test_body_ned_rotates_velocity_by_heading_only():
    """As measured on PX4: at yaw ~97 deg, body vx = 2 -> local (vx -0.24 N, vy +1.98 E)."""
    yaw = math.radians(97.0)
    sp = offboard.parse(8, 1991, ZERO3, (2.0, 0.0, -0.5), ZERO3, 0.0, 0.1, yaw)
    assert isinstance(sp, offboard.OffboardSetpoint)
    east, north, up = sp.velocity
    assert north == pytest.approx(2.0 * math.cos(yaw))
    assert east == pytest.approx(2.0 * math.sin(yaw))
    assert up == 0.5  # vz stays NED-down, just flipped to ENU-up
    assert sp.yaw_rate == -0.1  # NED yaw rate (clockwise) -> ENU (counter-clockwise)
    assert math.isnan(sp.yaw)  # ignored by mask 1991
    right = offboard.parse(8, 1991, ZERO3, (0.0, 1.0, 0.0), ZERO3, 0.0, 0.0, yaw)
    assert right.velocity[1] == pytest.approx(-math.sin(yaw))  # body right -> local -north


def test_local_position_mask_and_ignored_fields():
    sp = offboard.parse(1, 3064, (1.0, 2.0, -3.0), (9.0, 9.0, 9.0), ZERO3, 0.5, 9.0, 0.0)
    assert sp.position == (2.0, 1.0, 3.0)
    assert all(math.isnan(v) for v in sp.velocity)
    assert sp.yaw == pytest.approx(math.pi / 2 - 0.5)
    assert math.isnan(sp.yaw_rate)
    mixed = offboard.parse(8, 1987, (0, 0, -4.0), (1.0, 0.0, 0.0), ZERO3, 0.0, 0.2, 0.0)
    assert mixed.position[2] == 4.0 and math.isnan(mixed.position[0])
    assert mixed.velocity[1] == pytest.approx(1.0)  # forward at yaw 0 (north) = north


def test_nan_fields_are_not_controlled_and_counted():
    sp = offboard.parse(1, 1991, ZERO3, (math.nan, math.inf, 0.0), ZERO3, 0.0, 0.0, 0.0)
    assert sp.non_finite == 2
    assert math.isnan(sp.velocity[0]) and math.isnan(sp.velocity[1])
    all_ignored = offboard.parse(1, 0xFFF, ZERO3, ZERO3, ZERO3, 0.0, 0.0, 0.0)
    assert isinstance(all_ignored, offboard.Refusal) and all_ignored.statustext is None
