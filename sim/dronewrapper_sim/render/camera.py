"""Pinhole cameras on the vehicle: intrinsics, mounts and the projection of world points.

Frames: world points in local ENU (m); the vehicle orientation is a quaternion (x, y, z, w) rotating
body FLU into ENU (as MAVROS's pose orientation); a mount's position is in body FLU (m). The camera
frame is OpenCV's optical frame: x right, y down, z forward (depth). Pixels: (u, v) with u to the
right and v down, the centre of the top-left pixel at (0, 0), the optical axis at ``(cx, cy)``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

__all__ = [
    "FRONTAL",
    "NEAR_PLANE_M",
    "VENTRAL",
    "CameraMount",
    "CameraPose",
    "PinholeCamera",
    "camera_pose",
    "project",
    "quat_to_matrix",
    "yaw_to_quat",
]

NEAR_PLANE_M = 0.05
"""Points closer than this along the optical axis (or behind the camera) are not projected."""

# Camera axes (x right, y down, z forward) in body FLU for a mount pitched 0.
_BODY_FROM_CAMERA_LEVEL = np.array(
    [
        [0.0, 0.0, 1.0],
        [-1.0, 0.0, 0.0],
        [0.0, -1.0, 0.0],
    ]
)


@dataclass(frozen=True)
class PinholeCamera:
    """An ideal pinhole camera (no distortion) with square pixels.

    Attributes:
        width, height: image size, px.
        hfov_rad: horizontal field of view, rad.
    """

    width: int = 640
    height: int = 480
    hfov_rad: float = math.radians(60.0)

    def __post_init__(self) -> None:
        if self.width < 2 or self.height < 2:
            raise ValueError(f"image size must be at least 2x2 px, got {self.width}x{self.height}")
        if not 0.0 < self.hfov_rad < math.pi:
            raise ValueError(f"hfov_rad must be in (0, pi), got {self.hfov_rad}")

    @property
    def fx(self) -> float:
        """Focal length, px (horizontal)."""
        return (self.width / 2.0) / math.tan(self.hfov_rad / 2.0)

    @property
    def fy(self) -> float:
        """Focal length, px (vertical; square pixels, so equal to fx)."""
        return self.fx

    @property
    def cx(self) -> float:
        """Principal point u, px (the image centre)."""
        return (self.width - 1) / 2.0

    @property
    def cy(self) -> float:
        """Principal point v, px (the image centre)."""
        return (self.height - 1) / 2.0

    @property
    def vfov_rad(self) -> float:
        """Vertical field of view, rad."""
        return 2.0 * math.atan((self.height / 2.0) / self.fy)

    @property
    def matrix(self) -> np.ndarray:
        """The 3x3 intrinsic matrix K."""
        return np.array([[self.fx, 0.0, self.cx], [0.0, self.fy, self.cy], [0.0, 0.0, 1.0]])


@dataclass(frozen=True)
class CameraMount:
    """Where a camera sits on the vehicle.

    Attributes:
        name: the camera's name, used in its keys (``cam_frontal``, ``cam_ventral``).
        position_flu_m: camera centre in the body frame FLU, m.
        pitch_rad: rotation of the optical axis about body +y (left): 0 looks forward along body
            +x, +pi/2 looks straight down (body -z); the image top then points forward.
    """

    name: str
    position_flu_m: np.ndarray = field(default_factory=lambda: np.zeros(3))
    pitch_rad: float = 0.0

    @property
    def body_from_camera(self) -> np.ndarray:
        """Rotation matrix taking camera-frame vectors into body FLU."""
        c, s = math.cos(self.pitch_rad), math.sin(self.pitch_rad)
        rot_y = np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])
        return rot_y @ _BODY_FROM_CAMERA_LEVEL


FRONTAL = CameraMount("cam_frontal", np.array([0.12, 0.0, 0.05]), 0.0)
"""The forward-looking camera (level with the body, a little ahead of the centre)."""

VENTRAL = CameraMount("cam_ventral", np.array([0.0, 0.0, -0.06]), math.pi / 2.0)
"""The downward-looking camera (under the body; image top = vehicle forward)."""


def quat_to_matrix(quat_xyzw: np.ndarray) -> np.ndarray:
    """Rotation matrix of a quaternion (x, y, z, w); it is normalised first."""
    x, y, z, w = (float(v) for v in quat_xyzw)
    norm = math.sqrt(x * x + y * y + z * z + w * w)
    if not math.isfinite(norm) or norm < 1e-9:
        raise ValueError(f"invalid quaternion {tuple(quat_xyzw)}")
    x, y, z, w = x / norm, y / norm, z / norm, w / norm
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
        ]
    )


def yaw_to_quat(yaw_rad: float) -> np.ndarray:
    """Quaternion (x, y, z, w) of a level vehicle with heading ``yaw_rad`` (ENU, CCW from east)."""
    return np.array([0.0, 0.0, math.sin(yaw_rad / 2.0), math.cos(yaw_rad / 2.0)])


@dataclass(frozen=True)
class CameraPose:
    """A camera's pose in ENU: ``p_cam = world_to_camera @ (p_enu - position_enu)``."""

    position_enu: np.ndarray
    world_to_camera: np.ndarray

    @property
    def camera_to_world(self) -> np.ndarray:
        """Rotation taking camera-frame vectors into ENU."""
        return self.world_to_camera.T

    def to_camera(self, points_enu: np.ndarray) -> np.ndarray:
        """ENU points (N x 3, m) in the camera frame (N x 3, m; z = depth)."""
        pts = np.asarray(points_enu, dtype=np.float64).reshape(-1, 3)
        return (pts - self.position_enu) @ self.world_to_camera.T


def camera_pose(
    vehicle_pos_enu: np.ndarray, vehicle_quat_xyzw: np.ndarray, mount: CameraMount
) -> CameraPose:
    """The pose of ``mount``'s camera for a vehicle at ``vehicle_pos_enu`` (m) and attitude."""
    world_from_body = quat_to_matrix(vehicle_quat_xyzw)
    position = np.asarray(vehicle_pos_enu, dtype=np.float64).reshape(3)
    position = position + world_from_body @ np.asarray(mount.position_flu_m, dtype=np.float64)
    world_from_camera = world_from_body @ mount.body_from_camera
    return CameraPose(position, world_from_camera.T)


def project_camera_points(
    points_cam: np.ndarray, camera: PinholeCamera
) -> tuple[np.ndarray, np.ndarray]:
    """Project camera-frame points; pixels are NaN where depth < :data:`NEAR_PLANE_M`."""
    pts = np.asarray(points_cam, dtype=np.float64).reshape(-1, 3)
    depth = pts[:, 2].copy()
    pixels = np.full((len(pts), 2), np.nan)
    ok = depth >= NEAR_PLANE_M
    pixels[ok, 0] = camera.fx * pts[ok, 0] / depth[ok] + camera.cx
    pixels[ok, 1] = camera.fy * pts[ok, 1] / depth[ok] + camera.cy
    return pixels, depth


def project(
    points_enu: np.ndarray,
    vehicle_pos_enu: np.ndarray,
    vehicle_quat_xyzw: np.ndarray,
    mount: CameraMount,
    camera: PinholeCamera,
) -> tuple[np.ndarray, np.ndarray]:
    """Project world points into a vehicle camera's image.

    Args:
        points_enu: N x 3 (or 3) points in local ENU, m.
        vehicle_pos_enu: vehicle body origin in ENU, m.
        vehicle_quat_xyzw: vehicle attitude, body FLU -> ENU.
        mount: the camera's mount on the body.
        camera: its intrinsics.
    Returns:
        (pixels N x 2 (u, v) px, depth N m along the optical axis). Points behind the camera or
        closer than :data:`NEAR_PLANE_M` are culled: their pixels are NaN (their depth is still
        returned, <= 0 for points behind). Points outside the image are projected normally;
        check the bounds yourself.
    """
    pose = camera_pose(vehicle_pos_enu, vehicle_quat_xyzw, mount)
    return project_camera_points(pose.to_camera(points_enu), camera)
