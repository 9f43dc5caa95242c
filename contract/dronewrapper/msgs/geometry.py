"""Geometry messages shaped like ROS geometry_msgs (SI units, radians, right-handed frames).

Local frame: ENU fixed at the take-off point (x east, y north, z up), ``frame_id="map"``.
Body frame: FLU (x forward, y left, z up), ``frame_id="base_link"``.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import msgspec

from dronewrapper.msgs.std import Header

if TYPE_CHECKING:
    from typing_extensions import Self  # only for type checkers (typing's is Python 3.11)


class _XYZ(msgspec.Struct, frozen=True, kw_only=True):
    """Three components along x, y and z: the layout Point and Vector3 share."""

    x: float = 0.0
    y: float = 0.0
    z: float = 0.0

    @classmethod
    def of(cls, xyz: tuple[float, float, float]) -> Self:
        """The value with ``xyz`` as its (x, y, z)."""
        return cls(x=float(xyz[0]), y=float(xyz[1]), z=float(xyz[2]))


class Point(_XYZ, frozen=True, kw_only=True):
    """A position in metres."""


class Vector3(_XYZ, frozen=True, kw_only=True):
    """A free vector (velocity in m/s, angular rate in rad/s, ...)."""


class Quaternion(msgspec.Struct, kw_only=True, frozen=True):
    """A unit quaternion (Hamilton convention, x y z w as in ROS); identity by default."""

    x: float = 0.0
    y: float = 0.0
    z: float = 0.0
    w: float = 1.0


class Pose(msgspec.Struct, frozen=True, kw_only=True):
    """Position (m) and orientation of a body in a frame."""

    position: Point = msgspec.field(default_factory=Point)
    orientation: Quaternion = msgspec.field(default_factory=Quaternion)


class PoseStamped(msgspec.Struct, kw_only=True, frozen=True):
    """A stamped pose: vehicle pose in local ENU (``map``) for MAVROS-equivalent keys."""

    header: Header = msgspec.field(default_factory=Header)
    pose: Pose = msgspec.field(default_factory=Pose)


class Twist(msgspec.Struct, frozen=True, kw_only=True):
    """Linear velocity (m/s) and angular velocity (rad/s)."""

    linear: Vector3 = msgspec.field(default_factory=Vector3)
    angular: Vector3 = msgspec.field(default_factory=Vector3)


class TwistStamped(msgspec.Struct, kw_only=True, frozen=True):
    """A stamped twist; ``header.frame_id`` says the frame (``base_link`` FLU or ``map`` ENU)."""

    header: Header = msgspec.field(default_factory=Header)
    twist: Twist = msgspec.field(default_factory=Twist)
