"""The pose and the two velocities every bridge publishes of its vehicle (pure).

From one position (m, local ENU), attitude (body FLU in local ENU, quaternion x y z w) and local
velocity (m/s, ENU): the pose and the local velocity in the local frame (``map``, or ``odom``
where the position drifts), the body velocity (FLU) in ``base_link``. Each kind of message
numbers its own headers (:class:`Headers`).
"""

from __future__ import annotations

from dataclasses import dataclass, field

from dronewrapper.msgs import geometry
from dronewrapper.msgs.std import Header
from dronewrapper.rotations import Quat, Vec3, rotate_inverse

FRAME_BASE_LINK = "base_link"


@dataclass
class Headers:
    """Headers numbered per kind of message: ``seq`` counts from 1 for each ``what``."""

    seq: dict[str, int] = field(default_factory=dict)

    def __call__(self, frame_id: str, stamp: float, what: str) -> Header:
        self.seq[what] = self.seq.get(what, 0) + 1
        return Header(stamp=stamp, frame_id=frame_id, seq=self.seq[what])


def odometry(
    headers: Headers,
    frame_id: str,
    stamp: float,
    motion: tuple[Vec3, Quat, Vec3],
    rates_enu: geometry.Vector3,
    rates_flu: geometry.Vector3,
) -> tuple[geometry.PoseStamped, geometry.TwistStamped, geometry.TwistStamped]:
    """(pose ENU, velocity_local ENU, velocity_body FLU) stamped ``stamp`` (Unix s), for
    ``motion`` = (position m, attitude, velocity m/s) and the angular rates (rad/s) in the
    local frame (``rates_enu``) and the body's (``rates_flu``)."""
    position, attitude, velocity = motion
    x, y, z, w = attitude
    pose = geometry.PoseStamped(
        header=headers(frame_id, stamp, "pose"),
        pose=geometry.Pose(
            position=geometry.Point.of(position),
            orientation=geometry.Quaternion(x=x, y=y, z=z, w=w),
        ),
    )
    local = geometry.TwistStamped(
        header=headers(frame_id, stamp, "vlocal"),
        twist=geometry.Twist(linear=geometry.Vector3.of(velocity), angular=rates_enu),
    )
    body = geometry.TwistStamped(
        header=headers(FRAME_BASE_LINK, stamp, "vbody"),
        twist=geometry.Twist(
            linear=geometry.Vector3.of(rotate_inverse(attitude, velocity)), angular=rates_flu
        ),
    )
    return pose, local, body
