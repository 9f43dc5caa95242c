"""The true vehicle pose at one instant, shared by the physics loop, the cameras and the
ground-truth publisher."""

from __future__ import annotations

from dataclasses import dataclass

from dronewrapper.msgs.geometry import Point, Pose, PoseStamped, Quaternion
from dronewrapper.msgs.std import Header


@dataclass(frozen=True)
class PoseSnapshot:
    """The true vehicle pose at one instant: ENU position (m), quaternion x y z w (FLU->ENU),
    wall-clock time (s since the epoch)."""

    position: tuple[float, float, float]
    quaternion: tuple[float, float, float, float]
    stamp: float


def pose_msg(snapshot: PoseSnapshot, frame_id: str = "map", seq: int = 0) -> PoseStamped:
    """A PoseStamped of ``snapshot`` in local ENU."""
    x, y, z = snapshot.position
    qx, qy, qz, qw = snapshot.quaternion
    return PoseStamped(
        header=Header(stamp=snapshot.stamp, frame_id=frame_id, seq=seq),
        pose=Pose(position=Point(x=x, y=y, z=z), orientation=Quaternion(x=qx, y=qy, z=qz, w=qw)),
    )
