"""Rendered frames: the beacon is where and as big as projected, occlusion follows depth, the
background is free of red, and the ground shows motion."""

from __future__ import annotations

import math

import cv2
import numpy as np
import pytest

from dronewrapper_sim.render.camera import (
    FRONTAL,
    VENTRAL,
    PinholeCamera,
    camera_pose,
    project,
    yaw_to_quat,
)
from dronewrapper_sim.render.renderer import Renderer
from dronewrapper_sim.world.scenario import ObjectSpec, Scenario, load_scenario
from dronewrapper_sim.world.world import World

CAM = PinholeCamera(640, 480, math.radians(60.0))
LEVEL = yaw_to_quat(0.0)


def red_mask(bgr: np.ndarray) -> np.ndarray:
    """The paper's HSV red filter (H 0-10 and 340-359 deg, S >= 70, V >= 50) on a blurred image."""
    hsv = cv2.cvtColor(cv2.GaussianBlur(bgr, (5, 5), 0), cv2.COLOR_BGR2HSV)
    low = cv2.inRange(hsv, (0, 70, 50), (5, 255, 255))
    high = cv2.inRange(hsv, (170, 70, 50), (180, 255, 255))
    return cv2.bitwise_or(low, high)


def largest_red_circle(bgr: np.ndarray) -> tuple[float, float, float]:
    contours, _ = cv2.findContours(red_mask(bgr), cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_NONE)
    assert contours, "no red found"
    (u, v), r = cv2.minEnclosingCircle(max(contours, key=cv2.contourArea))
    return u, v, r


def world_of(*objects: ObjectSpec) -> World:
    return World(Scenario(name="t", objects=list(objects)))


@pytest.mark.parametrize(
    ("vehicle", "yaw_deg"),
    [((0.0, 0.0, 2.0), 0.0), ((1.0, -1.0, 1.2), 12.0), ((3.0, 0.5, 3.0), -20.0)],
)
def test_the_beacon_is_found_at_the_predicted_pixel_with_the_predicted_radius(vehicle, yaw_deg):
    world = World(load_scenario("beacon_static"))
    beacon = world.object("target")
    vehicle = np.array(vehicle)
    quat = yaw_to_quat(math.radians(yaw_deg))
    image = Renderer(world, CAM).render(FRONTAL, vehicle, quat)
    assert image.shape == (480, 640, 3) and image.dtype == np.uint8
    pixels, _ = project(beacon.position, vehicle, quat, FRONTAL, CAM)
    distance = float(
        np.linalg.norm(beacon.position - camera_pose(vehicle, quat, FRONTAL).position_enu)
    )
    predicted_radius = CAM.fx * beacon.radius_m / distance
    u, v, r = largest_red_circle(image)
    assert (u, v) == pytest.approx(tuple(pixels[0]), abs=1.5)
    assert r == pytest.approx(predicted_radius, rel=0.1)


def test_a_beacon_cut_by_the_border_is_drawn_partly():
    world = world_of(ObjectSpec(name="target", kind="beacon", position=(5.0, 0.0, 2.0)))
    beacon = world.object("target")
    vehicle = np.array([0.0, 0.0, 2.0])
    yaw = math.radians(30.0)  # the beacon sits on the right border of a 60 deg view
    image = Renderer(world, CAM).render(FRONTAL, vehicle, yaw_to_quat(yaw))
    pixels, _ = project(beacon.position, vehicle, yaw_to_quat(yaw), FRONTAL, CAM)
    u, v = pixels[0]
    r = CAM.fx * 0.3 / 5.0
    assert 639 < u < 639 + 0.8 * r  # centre outside, a good part inside
    mask = red_mask(image) > 0
    ys, xs = np.nonzero(mask)
    assert xs.size > 0 and xs.max() == 639
    assert abs(float(np.median(ys)) - v) < 2
    yy, xx = np.mgrid[0:480, 0:640]
    expected = ((xx - u) ** 2 + (yy - v) ** 2 <= r * r).sum()
    assert mask.sum() == pytest.approx(expected, rel=0.15)


def test_a_beacon_behind_the_camera_is_not_drawn():
    world = world_of(ObjectSpec(name="target", kind="beacon", position=(-5.0, 0.0, 2.0)))
    image = Renderer(world, CAM).render(FRONTAL, np.array([0.0, 0.0, 2.0]), LEVEL)
    assert not red_mask(image).any()


@pytest.mark.parametrize("name", ["empty", "person_static", "people_crossing_front"])
def test_nothing_but_the_beacon_is_red(name):
    world = World(load_scenario(name))
    renderer = Renderer(world, CAM)
    for _ in range(3):
        world.step(2.0)
        for mount, pos in (
            (FRONTAL, (0.0, 0.0, 1.5)),
            (FRONTAL, (0.0, 0.0, 0.0)),
            (VENTRAL, (5.0, 0.0, 3.0)),
        ):
            image = renderer.render(mount, np.array(pos), LEVEL)
            assert red_mask(image).sum() / 255 < 20  # a few anti-aliased pixels at most


def test_the_nearer_object_hides_the_farther_one():
    beacon = ObjectSpec(name="target", kind="beacon", position=(8.0, 0.0, 1.2))
    person = ObjectSpec(name="person1", kind="person", position=(4.0, 0.0, 0.0), height_m=1.8)
    vehicle = np.array([0.0, 0.0, 1.2])
    hidden = Renderer(world_of(beacon, person), CAM).render(FRONTAL, vehicle, LEVEL)
    assert red_mask(hidden).sum() / 255 < 10  # behind the torso
    # swap depths: the beacon in front of the person is fully visible
    beacon_front = ObjectSpec(name="target", kind="beacon", position=(3.0, 0.0, 1.2))
    person_back = ObjectSpec(name="person1", kind="person", position=(8.0, 0.0, 0.0))
    shown = Renderer(world_of(beacon_front, person_back), CAM).render(FRONTAL, vehicle, LEVEL)
    r = CAM.fx * 0.3 / 3.0
    assert red_mask(shown).sum() / 255 > 0.8 * math.pi * r * r


def test_the_image_size_follows_the_camera():
    small = PinholeCamera(320, 240, math.radians(65.0))
    image = Renderer(World(load_scenario("person_static")), small).render(
        VENTRAL, np.array([3.0, 0.0, 5.0]), LEVEL
    )
    assert image.shape == (240, 320, 3)


def test_rendering_is_deterministic_and_the_ground_shows_motion():
    world = World(load_scenario("empty"))
    renderer = Renderer(world, CAM)
    for mount, pos in ((VENTRAL, np.array([0.0, 0.0, 3.0])), (FRONTAL, np.array([0.0, 0.0, 2.0]))):
        a = renderer.render(mount, pos, LEVEL)
        b = renderer.render(mount, pos, LEVEL)
        assert np.array_equal(a, b)
        moved = renderer.render(mount, pos + np.array([0.3, 0.0, 0.0]), LEVEL)
        below = slice(300, 480)  # the ground in both views
        diff = np.abs(a[below].astype(int) - moved[below].astype(int)).mean()
        assert diff > 3.0, f"{mount.name}: the ground looks the same after moving 0.3 m"
        # and the texture is not flat: visible structure in the ground
        assert a[below].std() > 8.0


def test_sky_above_the_horizon_and_ground_below():
    image = Renderer(World(load_scenario("empty")), CAM).render(
        FRONTAL, np.array([0.0, 0.0, 2.0]), LEVEL
    )
    sky, ground = image[:150].reshape(-1, 3).mean(0), image[330:].reshape(-1, 3).mean(0)
    assert sky[0] > sky[2] + 40  # blue
    assert ground[1] > ground[0] + 30 and ground[1] > ground[2] + 20  # green


def test_the_skyline_shows_the_heading():
    """Distant trees above the horizon change as the vehicle turns in place."""
    renderer = Renderer(World(load_scenario("empty")), CAM)
    pos = np.array([0.0, 0.0, 2.0])
    band = slice(150, 236)  # just above the horizon (v = 239.5 for a level camera at 2 m)
    views = [renderer.render(FRONTAL, pos, yaw_to_quat(math.radians(a)))[band] for a in (0, 20)]
    diff = np.abs(views[0].astype(int) - views[1].astype(int)).mean()
    assert diff > 2.0
    bare = Renderer(World(load_scenario("empty")), CAM, scenery=False)
    plain = [bare.render(FRONTAL, pos, yaw_to_quat(math.radians(a)))[band] for a in (0, 20)]
    assert np.abs(plain[0].astype(int) - plain[1].astype(int)).mean() < 0.5  # sky is uniform
    assert not red_mask(renderer.render(FRONTAL, pos, LEVEL)).any()


def test_any_pose_renders_without_error():
    """Random attitudes (upside down included), altitudes from below ground to 300 m, positions
    far from the origin and right inside the objects: always a full frame, never an exception."""
    world = World(load_scenario("people_crossing_front"))
    world.objects.append(World(load_scenario("beacon_static")).objects[0])
    renderer = Renderer(world, PinholeCamera(160, 120, math.radians(60.0)))
    rng = np.random.default_rng(0)
    poses = [np.array([6.0, 0.0, 1.0]), np.array([6.0, 0.0, 2.0]), np.array([3.5, -5.0, 0.5])]
    poses += [rng.uniform([-500, -500, -1], [500, 500, 300]) for _ in range(30)]
    for pos in poses:
        quat = rng.normal(size=4)
        for mount in (FRONTAL, VENTRAL):
            image = renderer.render(mount, pos, quat)
            assert image.shape == (120, 160, 3) and image.dtype == np.uint8


@pytest.mark.parametrize("sprites", [False, True])
@pytest.mark.parametrize("yaw_deg", [180.0, 90.0])
def test_a_person_is_drawn_at_their_true_size_where_they_stand(sprites, yaw_deg):
    from support import SPRITES

    person = ObjectSpec(
        name="target", kind="person", position=(6.0, 1.0, 0.0), yaw=math.radians(yaw_deg)
    )
    world = world_of(person)
    vehicle = np.array([0.0, 0.0, 1.0])
    renderer = Renderer(world, CAM, SPRITES if sprites else None, scenery=False)
    image = renderer.render(FRONTAL, vehicle, LEVEL)
    world.objects.clear()
    empty = renderer.render(FRONTAL, vehicle, LEVEL)
    changed = np.abs(image.astype(int) - empty.astype(int)).sum(axis=2) > 40
    changed = cv2.morphologyEx(changed.astype(np.uint8), cv2.MORPH_OPEN, np.ones((3, 3)))
    ys, xs = np.nonzero(changed)
    obj = World(Scenario(name="t", objects=[person])).object("target")
    (foot, head), _ = project(np.array([obj.position, obj.top_enu]), vehicle, LEVEL, FRONTAL, CAM)
    height_px = foot[1] - head[1]
    assert ys.max() - ys.min() == pytest.approx(height_px, rel=0.08)
    assert ys.max() == pytest.approx(foot[1], abs=0.05 * height_px)
    assert np.median(xs) == pytest.approx(foot[0], abs=0.1 * height_px)
