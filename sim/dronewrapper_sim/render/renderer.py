"""The camera renderer: background, then every visible object far to near (painter's algorithm).

Pure: the image depends only on the world state and the camera pose. Objects behind the camera,
too far, or wholly outside the view are culled; those cut by the image border are drawn partly.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from dronewrapper_sim.render.background import Background
from dronewrapper_sim.render.beacon import draw_beacon, sphere_radius_px
from dronewrapper_sim.render.camera import (
    NEAR_PLANE_M,
    CameraMount,
    CameraPose,
    PinholeCamera,
    camera_pose,
    project_camera_points,
)
from dronewrapper_sim.render.person import draw_person
from dronewrapper_sim.render.shadow import draw_shadow
from dronewrapper_sim.render.sprites import draw_billboard, sprite_bank
from dronewrapper_sim.world.world import World, WorldObject

__all__ = ["MAX_DRAW_DISTANCE_M", "Renderer"]

MAX_DRAW_DISTANCE_M = 150.0
"""Objects farther than this from the camera are not drawn (they would be < 2 px)."""


class Renderer:
    """Renders the world's cameras.

    Args:
        world: the world whose objects are drawn (read at every :meth:`render`).
        camera: the intrinsics of the images produced.
        sprites_dir: a sprite folder (with ``sprites.json``) to draw people as photo billboards;
            None draws them procedurally.
        scenery: draw the distant trees and the clouds.
    """

    def __init__(
        self,
        world: World,
        camera: PinholeCamera,
        sprites_dir: Path | None = None,
        *,
        scenery: bool = True,
    ) -> None:
        self.world = world
        self.camera = camera
        self.background = Background(camera, seed=world.seed, scenery=scenery)
        self.sprites = sprite_bank(Path(sprites_dir)) if sprites_dir is not None else None

    def render(
        self, mount: CameraMount, vehicle_pos_enu: np.ndarray, vehicle_quat_xyzw: np.ndarray
    ) -> np.ndarray:
        """The image (H x W x 3 uint8 BGR) of ``mount``'s camera for the vehicle pose (ENU m,
        quaternion x, y, z, w body FLU -> ENU)."""
        pose = camera_pose(vehicle_pos_enu, vehicle_quat_xyzw, mount)
        image = self.background.render(pose)
        visible = []
        for obj in self.world.objects:
            depth = self._depth_if_visible(obj, pose)
            if depth is not None:
                visible.append((depth, obj))
        visible.sort(key=lambda item: -item[0])
        for _, obj in visible:
            draw_shadow(image, pose, self.camera, obj)
        for _, obj in visible:
            self._draw(image, pose, obj)
        return image

    def _depth_if_visible(self, obj: WorldObject, pose: CameraPose) -> float | None:
        """Depth (m) of the object's centre, or None if its bounding box cannot be in view."""
        cam = pose.to_camera(obj.center_enu)[0]
        if float(np.linalg.norm(cam)) > MAX_DRAW_DISTANCE_M:
            return None
        if obj.kind == "person":
            half = 0.45 * obj.height_m / 1.75  # arms and stride reach
            low, high = obj.position[2], obj.position[2] + obj.height_m
        else:
            half = obj.radius_m
            low, high = obj.position[2] - half, obj.position[2] + half
        corners = np.array(
            [
                (obj.position[0] + dx, obj.position[1] + dy, z)
                for dx in (-half, half)
                for dy in (-half, half)
                for z in (low, high)
            ]
        )
        box = pose.to_camera(corners)
        if np.all(box[:, 2] < NEAR_PLANE_M):
            return None  # wholly behind the camera
        if np.all(box[:, 2] >= NEAR_PLANE_M):
            c = self.camera
            u = c.fx * box[:, 0] / box[:, 2] + c.cx
            v = c.fy * box[:, 1] / box[:, 2] + c.cy
            if u.max() < -1 or u.min() > c.width or v.max() < -1 or v.min() > c.height:
                return None  # wholly outside the image
        return float(cam[2])

    def _draw(self, image: np.ndarray, pose: CameraPose, obj: WorldObject) -> None:
        if obj.kind == "beacon":
            cam = pose.to_camera(obj.position)
            pixels, _ = project_camera_points(cam, self.camera)
            if not math.isfinite(pixels[0, 0]):
                return
            radius = sphere_radius_px(self.camera.fx, obj.radius_m, float(np.linalg.norm(cam)))
            draw_beacon(image, (pixels[0, 0], pixels[0, 1]), radius, obj.color_bgr)
        elif self.sprites is not None:
            pts = pose.to_camera(np.array([obj.position, obj.top_enu]))
            pixels, _ = project_camera_points(pts, self.camera)
            if np.all(np.isfinite(pixels)):
                sprite = self.sprites.choose(obj.sprite, obj.sprite_index)
                draw_billboard(image, sprite, pixels[0], pixels[1])
        elif obj.look is not None:
            draw_person(
                image,
                pose,
                self.camera,
                obj.position,
                obj.yaw,
                obj.height_m,
                obj.walk_phase,
                obj.gait,
                obj.look,
            )
