"""A validated PositionTarget (ENU / FLU, the three controls of DESIGN) as what PX4's offboard
mode reads on Zenoh: an ``OffboardControlMode`` naming the controlled quantities and a
``TrajectorySetpoint`` in local NED, where NaN means "not controlled".

* position (mask 3064): position x, y, z and yaw;
* velocity (mask 1991): velocity (body FLU rotated by the heading, or local ENU) and yaw rate;
* mixed (mask 1987): horizontal velocity, altitude (z) and yaw rate; PX4 flies a NaN-filled
  TrajectorySetpoint natively, so no emulation is needed.

PX4 leaves offboard unless an OffboardControlMode arrives at least every 0.5 s; the bridge
sends one with every TrajectorySetpoint.
"""

from __future__ import annotations

import math
from typing import Any

from dronewrapper.msgs.mavros import FRAME_BODY_NED, PositionTarget
from dronewrapper_bridge_base.frames import enu_to_ned, heading_flu_to_enu, yaw_enu_to_ned
from dronewrapper_bridge_base.setpoint_limits import Kind

NAN = math.nan
_MODE_FIELDS = (
    "position",
    "velocity",
    "acceleration",
    "attitude",
    "body_rate",
    "thrust_and_torque",
    "direct_actuator",
)


def control_mode(kind: Kind) -> dict[str, Any]:
    """The OffboardControlMode for a control: position for position and mixed targets (PX4
    needs it for the altitude), velocity for velocity and mixed ones."""
    flags = dict.fromkeys(_MODE_FIELDS, False)
    flags["position"] = kind in (Kind.POSITION, Kind.MIXED)
    flags["velocity"] = kind in (Kind.VELOCITY, Kind.MIXED)
    return {"timestamp": 0, **flags}


def trajectory_setpoint(target: PositionTarget, kind: Kind, yaw_enu: float) -> dict[str, Any]:
    """The TrajectorySetpoint (NED m, m/s, rad, rad/s; NaN: free) for a target already
    validated as ``kind``; ``yaw_enu`` is the heading that rotates a body velocity (rad, ENU)."""
    position = [NAN, NAN, NAN]
    velocity = [NAN, NAN, NAN]
    yaw = yawspeed = NAN
    if kind is Kind.POSITION:
        p = target.position
        position = list(enu_to_ned((p.x, p.y, p.z)))
        yaw = yaw_enu_to_ned(target.yaw)
    else:
        v = target.velocity
        east, north = (
            heading_flu_to_enu(v.x, v.y, yaw_enu)
            if target.coordinate_frame == FRAME_BODY_NED
            else (v.x, v.y)
        )
        velocity = [north, east, -v.z]
        yawspeed = -target.yaw_rate  # CCW-positive (ENU) -> CW-positive (NED)
        if kind is Kind.MIXED:
            position[2] = -target.position.z
            velocity[2] = NAN
    return {
        "timestamp": 0,
        "position": position,
        "velocity": velocity,
        "acceleration": [NAN, NAN, NAN],
        "jerk": [NAN, NAN, NAN],
        "yaw": yaw,
        "yawspeed": yawspeed,
    }
