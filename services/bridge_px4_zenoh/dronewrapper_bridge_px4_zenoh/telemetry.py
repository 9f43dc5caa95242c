"""PX4's uORB telemetry (decoded px4_msgs values, NED / FRD, SI units) as the messages every
bridge publishes (ENU / FLU, as MAVROS). Pure: values in, messages out; ``stamp`` is the
wall-clock time (Unix s) the bridge stamps them with.
"""

from __future__ import annotations

import math
from typing import Any

from dronewrapper.msgs.geometry import PoseStamped, TwistStamped, Vector3
from dronewrapper.msgs.mavros import (
    LANDED_STATE_IN_AIR,
    LANDED_STATE_ON_GROUND,
    VTOL_STATE_MC,
    ExtendedState,
    State,
)
from dronewrapper.msgs.sensor import (
    NAVSAT_STATUS_FIX,
    NAVSAT_STATUS_NO_FIX,
    BatteryState,
    NavSatFix,
    NavSatStatus,
)
from dronewrapper.msgs.std import Header
from dronewrapper.rotations import Quat, Vec3
from dronewrapper_bridge_base.frames import attitude_ned_frd_to_enu_flu, ned_to_enu
from dronewrapper_bridge_base.odometry import Headers, odometry
from dronewrapper_bridge_px4_zenoh.modes import GUIDED_MODES, MANUAL_INPUT_MODES, mode_name

ARMED = 2  # VehicleStatus.ARMING_STATE_ARMED
AUTOPILOT = "px4"
MAP = "map"


def attitude_enu_flu(attitude: dict[str, Any]) -> Quat | None:
    """VehicleAttitude's ``q`` (w, x, y, z; body FRD in NED) as (x, y, z, w), body FLU in ENU;
    None while PX4 has no valid attitude (NaN)."""
    w, x, y, z = attitude["q"]
    if not all(math.isfinite(c) for c in (w, x, y, z)):
        return None
    return attitude_ned_frd_to_enu_flu((x, y, z, w))


def local_position(position: dict[str, Any]) -> Vec3 | None:
    """VehicleLocalPosition's position (NED m) in ``map`` (ENU m), or None while the horizontal
    or vertical position is not valid."""
    if not (position["xy_valid"] and position["z_valid"]):
        return None
    return ned_to_enu((position["x"], position["y"], position["z"]))


def local_velocity(position: dict[str, Any]) -> Vec3 | None:
    """VehicleLocalPosition's velocity (NED m/s) in ``map`` (ENU m/s), or None while not valid."""
    if not (position["v_xy_valid"] and position["v_z_valid"]):
        return None
    return ned_to_enu((position["vx"], position["vy"], position["vz"]))


def local_odometry(
    headers: Headers, position: Vec3, q_enu_flu: Quat, velocity: Vec3 | None, stamp: float
) -> tuple[PoseStamped, tuple[TwistStamped, TwistStamped] | None]:
    """The pose (``map``) at ``position`` (ENU m) and ``q_enu_flu`` and, unless ``velocity``
    (ENU m/s) is None (not valid), the local (``map``, ENU) and body (``base_link``, FLU)
    velocities, as every bridge publishes them (:func:`dronewrapper_bridge_base.odometry.odometry`).
    Angular rates are zero: the bridge does not read PX4's vehicle_angular_velocity."""
    motion = (position, q_enu_flu, velocity or (0.0, 0.0, 0.0))
    pose, local, body = odometry(headers, MAP, stamp, motion, Vector3(), Vector3())
    return pose, None if velocity is None else (local, body)


def state(status: dict[str, Any], *, connected: bool, failsafe: str, commander: str) -> State:
    """VehicleStatus as State (``failsafe`` and ``commander``: the bridge's own, as on every
    bridge)."""
    mode = mode_name(status["nav_state"])
    return State(
        connected=connected,
        armed=status["arming_state"] == ARMED,
        guided=mode in GUIDED_MODES,
        manual_input=mode in MANUAL_INPUT_MODES,
        mode=mode,
        system_status=4 if status["arming_state"] == ARMED else 3,  # MAV_STATE active / standby
        autopilot=AUTOPILOT,
        failsafe=failsafe,
        commander=commander,
    )


def extended_state(land: dict[str, Any], stamp: float) -> ExtendedState:
    """VehicleLandDetected as ExtendedState (on the ground while PX4 says ``landed``)."""
    landed = LANDED_STATE_ON_GROUND if land["landed"] else LANDED_STATE_IN_AIR
    return ExtendedState(header=Header(stamp=stamp), vtol_state=VTOL_STATE_MC, landed_state=landed)


def battery(status: dict[str, Any], stamp: float) -> BatteryState:
    """BatteryStatus as BatteryState (``remaining`` is a fraction, as ``percentage`` is)."""
    return BatteryState(
        header=Header(stamp=stamp),
        voltage=status["voltage_v"],
        current=status["current_a"],
        percentage=status["remaining"],
        present=bool(status["connected"]),
    )


def global_position(position: dict[str, Any], stamp: float) -> NavSatFix:
    """VehicleGlobalPosition (degrees, m AMSL) as NavSatFix; no fix while PX4's is not valid."""
    fix = position["lat_lon_valid"] and position["alt_valid"]
    return NavSatFix(
        header=Header(stamp=stamp, frame_id=MAP),
        status=NavSatStatus(status=NAVSAT_STATUS_FIX if fix else NAVSAT_STATUS_NO_FIX),
        latitude=position["lat"],
        longitude=position["lon"],
        altitude=position["alt"],
    )
