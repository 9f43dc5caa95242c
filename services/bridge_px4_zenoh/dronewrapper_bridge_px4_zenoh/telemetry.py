"""PX4's uORB telemetry (decoded px4_msgs values, NED / FRD, SI units) as the messages every
bridge publishes (ENU / FLU, as MAVROS). Pure: values in, messages out; ``stamp`` is the
wall-clock time (Unix s) the bridge stamps them with.
"""

from __future__ import annotations

import math
from typing import Any

from dronewrapper.msgs.geometry import (
    Point,
    Pose,
    PoseStamped,
    Quaternion,
    Twist,
    TwistStamped,
    Vector3,
)
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
from dronewrapper_bridge_base.frames import (
    attitude_ned_frd_to_enu_flu,
    ned_to_enu,
    rotate_inverse,
)
from dronewrapper_bridge_px4_zenoh.modes import GUIDED_MODES, MANUAL_INPUT_MODES, mode_name

ARMED = 2  # VehicleStatus.ARMING_STATE_ARMED
AUTOPILOT = "px4"
MAP, BASE_LINK = "map", "base_link"


def attitude_enu_flu(attitude: dict[str, Any]) -> tuple[float, float, float, float] | None:
    """VehicleAttitude's ``q`` (w, x, y, z; body FRD in NED) as (x, y, z, w), body FLU in ENU;
    None while PX4 has no valid attitude (NaN)."""
    w, x, y, z = attitude["q"]
    if not all(math.isfinite(c) for c in (w, x, y, z)):
        return None
    return attitude_ned_frd_to_enu_flu((x, y, z, w))


def local_pose(
    position: dict[str, Any], q_enu_flu: tuple[float, float, float, float], stamp: float
) -> PoseStamped | None:
    """VehicleLocalPosition (NED m) and the attitude as a pose in ``map`` (ENU), or None while
    the horizontal or vertical position is not valid."""
    if not (position["xy_valid"] and position["z_valid"]):
        return None
    east, north, up = ned_to_enu((position["x"], position["y"], position["z"]))
    x, y, z, w = q_enu_flu
    return PoseStamped(
        header=Header(stamp=stamp, frame_id=MAP),
        pose=Pose(
            position=Point(x=east, y=north, z=up), orientation=Quaternion(x=x, y=y, z=z, w=w)
        ),
    )


def local_velocity(position: dict[str, Any], stamp: float) -> TwistStamped | None:
    """VehicleLocalPosition's velocity (NED m/s) in ``map`` (ENU), or None while not valid."""
    if not (position["v_xy_valid"] and position["v_z_valid"]):
        return None
    east, north, up = ned_to_enu((position["vx"], position["vy"], position["vz"]))
    return TwistStamped(
        header=Header(stamp=stamp, frame_id=MAP),
        twist=Twist(linear=Vector3(x=east, y=north, z=up)),
    )


def body_velocity(
    velocity: TwistStamped, q_enu_flu: tuple[float, float, float, float]
) -> TwistStamped:
    """A local (ENU) velocity in ``base_link`` (FLU) at the attitude ``q_enu_flu``."""
    v = velocity.twist.linear
    fx, fy, fz = rotate_inverse(q_enu_flu, (v.x, v.y, v.z))
    return TwistStamped(
        header=Header(stamp=velocity.header.stamp, frame_id=BASE_LINK),
        twist=Twist(linear=Vector3(x=fx, y=fy, z=fz)),
    )


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
