"""SET_POSITION_TARGET_LOCAL_NED messages as a test's ground station streams them to the
simulated autopilot (m, m/s, rad, rad/s, in the MAVLink frame given)."""

from __future__ import annotations

import os

os.environ.setdefault("MAVLINK20", "1")

from pymavlink.dialects.v20 import common as mavlink

from dronewrapper.msgs.mavros import MASK_POSITION, MASK_VELOCITY

FRAME_LOCAL_NED = mavlink.MAV_FRAME_LOCAL_NED
FRAME_BODY_NED = mavlink.MAV_FRAME_BODY_NED


def velocity_target(vx=0.0, vy=0.0, vz=0.0, yaw_rate=0.0, frame=FRAME_BODY_NED):
    """Velocity (m/s) and yaw rate (rad/s) in ``frame``."""
    return mavlink.MAVLink_set_position_target_local_ned_message(
        0, 1, 1, frame, MASK_VELOCITY, 0, 0, 0, vx, vy, vz, 0, 0, 0, 0, yaw_rate
    )


def position_target(x: float, y: float, z: float, yaw: float = 0.0):
    """A local NED position (m) and heading (rad)."""
    return mavlink.MAVLink_set_position_target_local_ned_message(
        0, 1, 1, FRAME_LOCAL_NED, MASK_POSITION, x, y, z, 0, 0, 0, 0, 0, 0, yaw, 0
    )


def setpoint(vx=0.0, vy=0.0, vz=0.0, yaw_rate=0.0, frame=FRAME_BODY_NED, **pos):
    """A position target when ``pos`` gives x, y, z (and yaw), else a velocity target."""
    if pos:
        return position_target(pos["x"], pos["y"], pos["z"], pos.get("yaw", 0.0))
    return velocity_target(vx, vy, vz, yaw_rate, frame)
