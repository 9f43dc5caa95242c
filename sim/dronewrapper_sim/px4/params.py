"""PX4 parameters: the defaults table (with types) and the MAVLink value encoding.

PX4 sends integer parameters in PARAM_VALUE as raw int32 bits in the float field
(MAV_PARAM_TYPE_INT32, "bytewise" encoding): a client must reinterpret them, not cast them.
Reals are MAV_PARAM_TYPE_REAL32. Defaults are those read from PX4 SITL (1.17 development line,
airframe 10040 sihsim_quadx); units are PX4's (m, m/s, s, deg).
"""

from __future__ import annotations

import math
import struct
from dataclasses import dataclass

from pymavlink.dialects.v20 import common as mavlink

INT32 = "INT32"
FLOAT = "FLOAT"


@dataclass(frozen=True)
class ParamDef:
    """One parameter: name (<= 16 chars), type (INT32 or FLOAT), default, unit, meaning."""

    name: str
    type: str
    default: float
    unit: str = ""
    doc: str = ""


DEFAULTS: tuple[ParamDef, ...] = (
    ParamDef("SYS_AUTOSTART", INT32, 10040, "", "airframe: sihsim_quadx"),
    ParamDef("MAV_SYS_ID", INT32, 1, "", "MAVLink system id"),
    ParamDef("MAV_COMP_ID", INT32, 1, "", "MAVLink component id"),
    ParamDef("MAV_TYPE", INT32, 2, "", "MAV_TYPE_QUADROTOR"),
    ParamDef("COM_RC_IN_MODE", INT32, 1, "", "1: joystick/MAVLink only, no RC"),
    ParamDef("COM_ARM_WO_GPS", INT32, 1, "", "allow arming without GPS"),
    ParamDef("COM_OF_LOSS_T", FLOAT, 1.0, "s", "offboard signal lost after this gap"),
    ParamDef("COM_OBL_RC_ACT", INT32, 0, "", "offboard loss action (0 position, needs RC)"),
    ParamDef("COM_OBC_LOSS_T", FLOAT, 5.0, "s", "onboard computer loss timeout"),
    ParamDef("COM_FAIL_ACT_T", FLOAT, 5.0, "s", "failsafe hold delay (with RC only)"),
    ParamDef("COM_DISARM_PRFLT", FLOAT, 10.0, "s", "auto-disarm if no take-off after arming"),
    ParamDef("COM_DISARM_LAND", FLOAT, 2.0, "s", "auto-disarm after landing"),
    ParamDef("COM_SPOOLUP_TIME", FLOAT, 1.0, "s", "motor spool-up before lift-off"),
    ParamDef("NAV_RCL_ACT", INT32, 2, "", "RC loss action: 2 return"),
    ParamDef("NAV_DLL_ACT", INT32, 0, "", "GCS link loss action: 0 none"),
    ParamDef("NAV_ACC_RAD", FLOAT, 2.0, "m", "waypoint acceptance radius"),
    ParamDef("MIS_TAKEOFF_ALT", FLOAT, 2.5, "m", "take-off altitude above home"),
    ParamDef("RTL_RETURN_ALT", FLOAT, 30.0, "m", "return altitude above home"),
    ParamDef("RTL_DESCEND_ALT", FLOAT, 10.0, "m", "altitude of the descent over home"),
    ParamDef("RTL_LAND_DELAY", FLOAT, 0.0, "s", "hover over home before landing"),
    ParamDef("RTL_MIN_DIST", FLOAT, 10.0, "m", "closer than this to home: land straight away"),
    ParamDef("MPC_XY_VEL_MAX", FLOAT, 12.0, "m/s", "horizontal speed limit"),
    ParamDef("MPC_XY_CRUISE", FLOAT, 5.0, "m/s", "horizontal speed of automatic modes"),
    ParamDef("MPC_Z_VEL_MAX_UP", FLOAT, 3.0, "m/s", "climb speed limit"),
    ParamDef("MPC_Z_VEL_MAX_DN", FLOAT, 1.5, "m/s", "descent speed limit"),
    ParamDef("MPC_Z_V_AUTO_UP", FLOAT, 3.0, "m/s", "climb speed of automatic modes"),
    ParamDef("MPC_Z_V_AUTO_DN", FLOAT, 1.0, "m/s", "descent speed of automatic modes"),
    ParamDef("MPC_TILTMAX_AIR", FLOAT, 45.0, "deg", "tilt limit in flight"),
    ParamDef("MPC_TKO_SPEED", FLOAT, 1.5, "m/s", "take-off climb speed"),
    ParamDef("MPC_TKO_RAMP_T", FLOAT, 3.0, "s", "take-off speed ramp time"),
    ParamDef("MPC_LAND_SPEED", FLOAT, 0.7, "m/s", "final landing descent speed"),
    ParamDef("MPC_LAND_ALT1", FLOAT, 10.0, "m", "start slowing the landing descent"),
    ParamDef("MPC_LAND_ALT2", FLOAT, 5.0, "m", "below this, descend at MPC_LAND_SPEED"),
    ParamDef("MPC_XY_P", FLOAT, 0.95, "1/s", "horizontal position gain"),
    ParamDef("MPC_Z_P", FLOAT, 1.0, "1/s", "vertical position gain"),
    ParamDef("MPC_XY_VEL_P_ACC", FLOAT, 1.8, "1/s", "horizontal velocity P gain"),
    ParamDef("MPC_XY_VEL_I_ACC", FLOAT, 0.4, "1/s^2", "horizontal velocity I gain"),
    ParamDef("MPC_Z_VEL_P_ACC", FLOAT, 4.0, "1/s", "vertical velocity P gain"),
    ParamDef("MPC_Z_VEL_I_ACC", FLOAT, 2.0, "1/s^2", "vertical velocity I gain"),
    ParamDef("MPC_ACC_HOR_MAX", FLOAT, 5.0, "m/s^2", "horizontal acceleration (auto modes)"),
    ParamDef("MPC_THR_HOVER", FLOAT, 0.5, "", "hover thrust"),
    ParamDef("MPC_YAWRAUTO_MAX", FLOAT, 45.0, "deg/s", "yaw rate of automatic modes"),
    ParamDef("MC_YAWRATE_MAX", FLOAT, 200.0, "deg/s", "yaw rate limit"),
    ParamDef("MPC_YAW_P", FLOAT, 2.8, "1/s", "yaw (heading) gain (MC_YAW_P)"),
    ParamDef("LNDMC_TRIG_TIME", FLOAT, 1.0, "s", "landing detector trigger time"),
    ParamDef("LNDMC_Z_VEL_MAX", FLOAT, 0.5, "m/s", "landing detector vertical speed"),
    ParamDef("BAT1_N_CELLS", INT32, 4, "", "battery cells in series"),
    ParamDef("BAT1_CAPACITY", FLOAT, 5000.0, "mAh", "battery capacity"),
    ParamDef("BAT1_V_CHARGED", FLOAT, 4.05, "V", "cell voltage when full"),
    ParamDef("BAT1_V_EMPTY", FLOAT, 3.6, "V", "cell voltage when empty"),
    ParamDef("GF_ACTION", INT32, 2, "", "geofence action"),
    ParamDef("EKF2_HGT_REF", INT32, 1, "", "height reference: GPS"),
    ParamDef("SDLOG_MODE", INT32, 0, "", "logging mode"),
)

_BY_NAME = {p.name: p for p in DEFAULTS}


def int32_to_float_bits(value: int) -> float:
    """The float whose bytes are the int32 ``value`` (PX4's bytewise int32 encoding)."""
    return struct.unpack("<f", struct.pack("<i", int(value)))[0]


def float_bits_to_int32(value: float) -> int:
    """The int32 carried bytewise in the float ``value`` (inverse of int32_to_float_bits)."""
    return struct.unpack("<i", struct.pack("<f", value))[0]


class ParamStore:
    """The parameter table of one vehicle: typed values, index order and MAVLink encoding."""

    def __init__(self, overrides: dict[str, float] | None = None) -> None:
        self.defs: tuple[ParamDef, ...] = DEFAULTS
        self._values: dict[str, float] = {p.name: p.default for p in DEFAULTS}
        self.version = 0  # incremented by every set(): lets users cache derived values
        for name, value in (overrides or {}).items():
            self.set(name, value)

    def __contains__(self, name: str) -> bool:
        return name in self._values

    def __getitem__(self, name: str) -> float:
        return self._values[name]

    def __len__(self) -> int:
        return len(self.defs)

    def get(self, name: str) -> float:
        """The value of ``name`` (int for INT32 params). KeyError if unknown."""
        return self._values[name]

    def set(self, name: str, value: float) -> float:
        """Set ``name`` to ``value`` (converted to the param's type); returns the stored value.

        Raises:
            KeyError: unknown parameter.
            ValueError: a non-finite value, or an INT32 value out of range.
        """
        pdef = _BY_NAME[name]
        if not math.isfinite(value):
            raise ValueError(f"{name}: value must be finite, got {value}")
        if pdef.type == INT32 and not -(2**31) <= value < 2**31:
            raise ValueError(f"{name}: {value} does not fit an int32")
        stored: float = int(value) if pdef.type == INT32 else float(value)
        self._values[name] = stored
        self.version += 1
        return stored

    def index(self, name: str) -> int:
        """The param's index in PARAM_VALUE (its position in the table)."""
        return list(_BY_NAME).index(name)

    def name_at(self, index: int) -> str | None:
        """The name of the param at ``index``, or None if out of range."""
        return self.defs[index].name if 0 <= index < len(self.defs) else None

    def type_of(self, name: str) -> int:
        """The MAV_PARAM_TYPE of ``name``."""
        return (
            mavlink.MAV_PARAM_TYPE_INT32
            if _BY_NAME[name].type == INT32
            else mavlink.MAV_PARAM_TYPE_REAL32
        )

    def wire_value(self, name: str) -> float:
        """The float carried in PARAM_VALUE (int32 params as raw bits)."""
        value = self._values[name]
        if _BY_NAME[name].type == INT32:
            return int32_to_float_bits(int(value))
        return float(value)

    def from_wire(self, name: str, wire: float, param_type: int) -> float:
        """Decode a PARAM_SET float for ``name`` sent with ``param_type``."""
        if param_type in (1, 2, 3, 4, 5, 6):  # UINT8..INT32: bytewise in the float
            return float(float_bits_to_int32(wire))
        return wire
