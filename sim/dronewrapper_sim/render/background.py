"""The background of every frame: a textured ground plane fading into haze, a sky gradient with
clouds, and distant trees (``scenery.py``).

The ground is a seamless grass texture (an 8 m tile with a faint 2 m mowing checker, so motion
and heading are visible) mapped onto the plane z = 0 with one homography
(``cv2.warpPerspective``). The texture image covers +-24 m around the camera (the tile is
periodic, so it is re-anchored on the tile grid under the camera) and is pre-blurred with distance
(a poor man's mip-map against shimmering); farther ground is its mean colour. Distance haze and the
sky are computed on a coarse grid and up-sampled.
"""

from __future__ import annotations

import math
from functools import lru_cache

import cv2
import numpy as np

from dronewrapper_sim.render.camera import CameraPose, PinholeCamera
from dronewrapper_sim.render.scenery import draw_trees, make_trees

__all__ = ["GROUND_TILE_M", "Background", "make_grass_tile"]

GROUND_TILE_M = 8.0
"""Period of the ground texture, m."""
TEXTURE_RES_M = 0.025  # m per texture pixel
TEXTURE_REACH_TILES = 3  # the texture covers this many tiles on each side of the camera's tile
FOG_DISTANCE_M = 70.0  # haze: alpha = 1 - exp(-(distance - HAZE_START_M) / FOG_DISTANCE_M)
HAZE_START_M = 8.0  # no haze nearer than this (and no blending cost for a downward camera)
CACHED_POSES = 4  # background images kept for repeated poses
GRID_STEP_PX = 8  # haze and sky are computed every GRID_STEP_PX pixels and up-sampled

SKY_HORIZON_BGR = np.array([228.0, 212.0, 196.0])
SKY_ZENITH_BGR = np.array([205.0, 140.0, 75.0])
CLOUD_BGR = np.array([248.0, 246.0, 244.0])
CLOUD_SHADE_BGR = np.array([200.0, 192.0, 188.0])
CLOUD_ALTITUDE_M = 1500.0
CLOUD_TILE_M = 6000.0  # the cloud pattern repeats every this many metres
CLOUD_TILE_PX = 256


def _periodic_noise(rng: np.random.Generator, size: int, sigma_px: float) -> np.ndarray:
    """Seamless (periodic) smooth noise, zero mean, unit std."""
    white = rng.standard_normal((size, size))
    f = np.fft.fftfreq(size)
    fx, fy = np.meshgrid(f, f)
    kernel = np.exp(-2.0 * (math.pi * sigma_px) ** 2 * (fx**2 + fy**2))
    noise = np.real(np.fft.ifft2(np.fft.fft2(white) * kernel))
    return (noise - noise.mean()) / (noise.std() + 1e-12)


def make_grass_tile(seed: int = 0, tile_m: float = GROUND_TILE_M, res_m: float = TEXTURE_RES_M):
    """A seamless grass tile (BGR uint8) of ``tile_m`` metres at ``res_m`` m/px."""
    size = round(tile_m / res_m)
    rng = np.random.default_rng(seed)
    base = np.array([52.0, 128.0, 78.0])  # BGR grass
    patches = _periodic_noise(rng, size, 40.0)  # ~1 m patches
    blotches = _periodic_noise(rng, size, 10.0)
    blades = _periodic_noise(rng, size, 0.8)
    dry = np.clip(_periodic_noise(rng, size, 25.0) - 0.8, 0.0, None)  # sparse dry spots
    shade = 1.0 + 0.10 * patches + 0.06 * blotches + 0.10 * blades
    # faint 2 m checker (mowing pattern) so motion is visible even far away
    idx = (np.arange(size) * res_m // 2.0).astype(int)
    checker = ((idx[None, :] + idx[:, None]) % 2) * 2.0 - 1.0
    shade += 0.06 * checker
    tile = base[None, None, :] * shade[:, :, None]
    dry_color = np.array([70.0, 150.0, 160.0])
    mix = np.clip(dry * 0.9, 0.0, 0.7)[:, :, None]
    tile = tile * (1.0 - mix) + dry_color * mix
    return np.clip(tile, 0, 255).astype(np.uint8)


@lru_cache(maxsize=4)
def ground_texture(seed: int) -> tuple[np.ndarray, tuple[float, float, float]]:
    """The ground texture image for a seed (built once per process; read-only) and its mean
    colour (BGR)."""
    tile = make_grass_tile(seed)
    texture = _ground_texture(tile, TEXTURE_REACH_TILES)
    texture.setflags(write=False)
    mean = tuple(float(v) for v in tile.reshape(-1, 3).mean(axis=0))
    return texture, mean  # type: ignore[return-value]


@lru_cache(maxsize=4)
def cloud_tile(seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """Seamless cloud cover (0..1) and cloud shading (0 lit .. 1 shaded), float32 tiles."""
    rng = np.random.default_rng([seed, 11])
    n = CLOUD_TILE_PX
    big = _periodic_noise(rng, n, 14.0)
    small = _periodic_noise(rng, n, 3.0)
    field = big + 0.35 * small
    cover = np.clip((field - 0.5) * 0.9, 0.0, 0.9).astype(np.float32)
    shade = np.clip(0.5 - 0.5 * small, 0.0, 1.0).astype(np.float32)
    return cover, shade


def _periodic_blur(tile: np.ndarray, sigma_px: float) -> np.ndarray:
    """Gaussian blur of a seamless tile that stays seamless (wrap-around borders)."""
    pad = min(tile.shape[0], math.ceil(3.0 * sigma_px) + 1)
    padded = cv2.copyMakeBorder(tile, pad, pad, pad, pad, cv2.BORDER_WRAP)
    blurred = cv2.GaussianBlur(padded, (0, 0), sigma_px)
    return blurred[pad:-pad, pad:-pad]


def _ground_texture(tile: np.ndarray, reach: int) -> np.ndarray:
    """The tile repeated (2 * reach + 1) times per side, blurred more the farther from the
    centre tile (where the camera is)."""
    n = 2 * reach + 1
    out = np.tile(tile, (n, n, 1))
    size = out.shape[0]
    c = (size - 1) / 2.0
    coords = (np.arange(size, dtype=np.float32) - c) * np.float32(n * GROUND_TILE_M / size)
    r = np.sqrt(coords[None, :] ** 2 + coords[:, None] ** 2)  # m from the centre
    for sigma, r0, ramp in ((1.5, 6.0, 4.0), (4.0, 12.0, 6.0), (10.0, 20.0, 6.0)):
        blurred = np.tile(_periodic_blur(tile, sigma), (n, n, 1))
        w = np.clip((r - r0) / ramp, 0.0, 1.0)
        out = cv2.blendLinear(out, blurred, 1.0 - w, w)
    return out


class Background:
    """Renders sky and ground for one camera model (intrinsics fixed at construction).

    The background is smooth (haze, sky, a ground texture that is blurred with distance), so it
    is rendered at 1/``scale`` of the resolution and up-sampled once; objects are then drawn
    on top at full resolution.
    """

    def __init__(
        self, camera: PinholeCamera, seed: int = 0, scale: int = 2, scenery: bool = True
    ) -> None:
        if scale < 1:
            raise ValueError(f"scale must be >= 1, got {scale}")
        self.camera = camera
        self.scale = scale
        self.texture, self.far_bgr = ground_texture(seed)
        self.trees = make_trees(seed) if scenery else None
        self.clouds = cloud_tile(seed) if scenery else None
        self._cache: dict[bytes, np.ndarray] = {}
        self.work_w = math.ceil(camera.width / scale)
        self.work_h = math.ceil(camera.height / scale)
        # working-resolution intrinsics: u_work = (u + 0.5) / scale - 0.5 (cv2.resize's mapping)
        self.work_matrix = np.array(
            [
                [camera.fx / scale, 0.0, (camera.cx + 0.5) / scale - 0.5],
                [0.0, camera.fy / scale, (camera.cy + 0.5) / scale - 0.5],
                [0.0, 0.0, 1.0],
            ]
        )
        step = max(1, GRID_STEP_PX // scale)
        self.grid_step = step
        self.grid_w = math.ceil(self.work_w / step)
        self.grid_h = math.ceil(self.work_h / step)
        us = (np.arange(self.grid_w) + 0.5) * step - 0.5
        vs = (np.arange(self.grid_h) + 0.5) * step - 0.5
        uu, vv = np.meshgrid(us, vs)
        k = self.work_matrix
        # rays in the camera frame, one per grid point (x right, y down, z forward)
        self.rays_cam = np.stack(
            ((uu - k[0, 2]) / k[0, 0], (vv - k[1, 2]) / k[1, 1], np.ones_like(uu)), -1
        ).reshape(-1, 3)

    def _haze_and_sky(self, pose: CameraPose) -> tuple[np.ndarray, np.ndarray]:
        """(alpha float32: 1 = sky/haze only, colour BGR uint8), at the working resolution."""
        rays = self.rays_cam @ pose.camera_to_world.T  # ENU directions
        norm = np.linalg.norm(rays, axis=1)
        up = rays[:, 2] / norm  # sin(elevation)
        height = max(float(pose.position_enu[2]), 0.02)
        down = up < -1e-6
        dist = np.full(up.shape, np.inf)
        # horizontal distance to where the ray meets the ground
        horiz = np.sqrt(np.maximum(1.0 - up**2, 0.0))
        dist[down] = height * horiz[down] / -up[down]
        alpha = 1.0 - np.exp(-np.maximum(dist - HAZE_START_M, 0.0) / FOG_DISTANCE_M)
        t = 1.0 - np.exp(-np.clip(up, 0.0, None) / 0.3)
        color = SKY_HORIZON_BGR + (SKY_ZENITH_BGR - SKY_HORIZON_BGR) * t[:, None]
        if self.clouds is not None:
            self._add_clouds(color, rays / norm[:, None], pose.position_enu)
        shape = (self.grid_h, self.grid_w)
        step = self.grid_step
        size = (self.grid_w * step, self.grid_h * step)
        w, h = self.work_w, self.work_h
        alpha_img = cv2.resize(alpha.reshape(shape).astype(np.float32), size)[:h, :w]
        color_img = cv2.resize(color.reshape(*shape, 3).astype(np.uint8), size)[:h, :w]
        return alpha_img, color_img

    def _add_clouds(self, color: np.ndarray, dirs: np.ndarray, position: np.ndarray) -> None:
        """Blend clouds on a flat layer at CLOUD_ALTITUDE_M into the sky colours (in place)."""
        up = dirs[:, 2]
        sky = np.nonzero(up > 0.02)[0]
        if sky.size == 0:
            return
        d = dirs[sky]
        reach = (CLOUD_ALTITUDE_M - float(position[2])) / d[:, 2]
        scale = CLOUD_TILE_PX / CLOUD_TILE_M
        gx = (float(position[0]) + d[:, 0] * reach) * scale
        gy = (float(position[1]) + d[:, 1] * reach) * scale
        x0, y0 = np.floor(gx), np.floor(gy)
        fx, fy = gx - x0, gy - y0
        n = CLOUD_TILE_PX
        ix0, iy0 = x0.astype(np.int64) % n, y0.astype(np.int64) % n
        ix1, iy1 = (ix0 + 1) % n, (iy0 + 1) % n

        def sample(tile: np.ndarray) -> np.ndarray:
            top = tile[iy0, ix0] * (1 - fx) + tile[iy0, ix1] * fx
            bottom = tile[iy1, ix0] * (1 - fx) + tile[iy1, ix1] * fx
            return top * (1 - fy) + bottom * fy

        assert self.clouds is not None
        cover_tile, shade_tile = self.clouds
        cover = sample(cover_tile) * np.clip((up[sky] - 0.02) / 0.2, 0.0, 1.0)
        shade = sample(shade_tile)[:, None]
        cloud = CLOUD_BGR * (1.0 - shade) + CLOUD_SHADE_BGR * shade
        color[sky] = color[sky] * (1.0 - cover[:, None]) + cloud * cover[:, None]

    def ground_homography(self, pose: CameraPose) -> np.ndarray:
        """Homography from texture px to working-resolution image px."""
        r = pose.world_to_camera
        position = pose.position_enu.copy()
        position[2] = max(position[2], 0.02)
        t = -r @ position
        ground_to_image = self.work_matrix @ np.column_stack((r[:, 0], r[:, 1], t))
        reach = TEXTURE_REACH_TILES * GROUND_TILE_M
        ox = math.floor(position[0] / GROUND_TILE_M) * GROUND_TILE_M - reach
        oy = math.floor(position[1] / GROUND_TILE_M) * GROUND_TILE_M + GROUND_TILE_M + reach
        res = TEXTURE_RES_M
        texture_to_ground = np.array([[res, 0.0, ox], [0.0, -res, oy], [0.0, 0.0, 1.0]])
        return ground_to_image @ texture_to_ground

    def render(self, pose: CameraPose) -> np.ndarray:
        """The background image (H x W x 3 BGR uint8, a new array) seen from ``pose``.

        The last few poses' images are kept, so a vehicle standing still (on the ground, or
        each of its cameras in turn) costs only a copy.
        """
        key = pose.position_enu.tobytes() + pose.world_to_camera.tobytes()
        cached = self._cache.get(key)
        if cached is None:
            cached = self._render(pose)
            cached.setflags(write=False)
            if len(self._cache) >= CACHED_POSES:
                self._cache.pop(next(iter(self._cache)))
            self._cache[key] = cached
        return cached.copy()

    def _render(self, pose: CameraPose) -> np.ndarray:
        alpha, image = self._haze_and_sky(pose)
        ground_rows = np.nonzero(alpha.min(axis=1) < 0.995)[0]
        if ground_rows.size:
            y0, y1 = int(ground_rows[0]), int(ground_rows[-1]) + 1
            shift = np.array([[1.0, 0.0, 0.0], [0.0, 1.0, -y0], [0.0, 0.0, 1.0]])
            ground = cv2.warpPerspective(
                self.texture,
                shift @ self.ground_homography(pose),
                (self.work_w, y1 - y0),
                flags=cv2.INTER_LINEAR,
                borderMode=cv2.BORDER_CONSTANT,
                borderValue=self.far_bgr,
            )
            # blend only the rows with visible haze; nearer rows are plain ground
            hazy = np.nonzero(alpha[y0:y1].max(axis=1) >= 0.004)[0]
            blended = None
            if hazy.size:
                h0, h1 = y0 + int(hazy[0]), y0 + int(hazy[-1]) + 1
                a = alpha[h0:h1]
                blended = cv2.blendLinear(ground[h0 - y0 : h1 - y0], image[h0:h1], 1.0 - a, a)
            image[y0:y1] = ground
            if blended is not None:
                image[h0:h1] = blended
        if self.trees is not None:
            draw_trees(image, self.trees, pose, self.work_matrix, SKY_HORIZON_BGR, FOG_DISTANCE_M)
        if self.scale == 1:
            return image
        s = self.scale
        full = cv2.resize(image, (self.work_w * s, self.work_h * s), interpolation=cv2.INTER_LINEAR)
        return full[: self.camera.height, : self.camera.width]
