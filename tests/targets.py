"""PositionTargets as the tests send them, built as they are written (no validation: a test may
hand a bridge a bad value on purpose).

``velocity``: m/s and rad/s in ``frame`` (``FRAME_BODY_NED`` by default); ``mixed``: a body-frame
horizontal velocity with a height (m); ``position``: a local point (m) with a heading (rad).
"""

from __future__ import annotations

from dronewrapper.msgs import mavros
from dronewrapper.msgs.geometry import Point, Vector3


def velocity(
    vx: float = 0.0,
    vy: float = 0.0,
    vz: float = 0.0,
    yaw_rate: float = 0.0,
    *,
    frame: int = mavros.FRAME_BODY_NED,
    mask: int = mavros.MASK_VELOCITY,
) -> mavros.PositionTarget:
    """A velocity target (``mask``: another type mask, to send a velocity under it)."""
    velocity = Vector3(x=vx, y=vy, z=vz)
    return mavros.PositionTarget(
        coordinate_frame=frame, type_mask=mask, velocity=velocity, yaw_rate=yaw_rate
    )


def mixed(
    vx: float = 0.0, z: float = 0.0, yaw_rate: float = 0.0, *, vy: float = 0.0
) -> mavros.PositionTarget:
    """A body-frame horizontal velocity at the height ``z``."""
    return mavros.PositionTarget(
        coordinate_frame=mavros.FRAME_BODY_NED,
        type_mask=mavros.MASK_MIXED,
        velocity=Vector3(x=vx, y=vy),
        position=Point(z=z),
        yaw_rate=yaw_rate,
    )


def position(
    x: float = 0.0, y: float = 0.0, z: float = 0.0, yaw: float = 0.0
) -> mavros.PositionTarget:
    """A local position with a heading."""
    point = Point(x=x, y=y, z=z)
    return mavros.PositionTarget(
        coordinate_frame=mavros.FRAME_LOCAL_NED,
        type_mask=mavros.MASK_POSITION,
        position=point,
        yaw=yaw,
    )
